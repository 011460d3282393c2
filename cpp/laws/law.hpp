// The friction laws by name, and the one place that turns a run-time law into its policy type.
#pragma once
#include <string>
#include "laws/coulomb.hpp"
#include "laws/frictionless.hpp"
#include "laws/linear.hpp"
#include "laws/tresca.hpp"

namespace cmg {

enum class Law : int { Linear = 0, Frictionless = 1, Tresca = 2, Coulomb = 3 };

inline Law parse_law(const std::string& s) {
  if (s == "linear") return Law::Linear;
  if (s == "frictionless") return Law::Frictionless;
  if (s == "tresca") return Law::Tresca;
  if (s == "coulomb") return Law::Coulomb;
  throw InputError("unknown friction law '" + s + "' (expected linear, frictionless, tresca or coulomb)");
}

// f(policy{}) for the law l.
template <class F>
auto with_law(Law l, F&& f) {
  switch (l) {
    case Law::Frictionless: return f(law::Frictionless{});
    case Law::Tresca: return f(law::Tresca{});
    case Law::Coulomb: return f(law::Coulomb{});
    case Law::Linear: break;
  }
  return f(law::Linear{});
}

}  // namespace cmg
