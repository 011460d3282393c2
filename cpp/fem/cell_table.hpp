// The one table of cell types: everything the core and the Python package need to know about a
// cell (name, dimension, nodes, facets with their local nodes and facet type). Python reads it
// through _core.cell_table(); C++ dispatches on it with dispatch_cell.
#pragma once
#include <array>
#include <string>
#include <type_traits>
#include "base/common.hpp"

namespace cmg {

enum class CellType : int { Triangle = 0, Quad = 1, Tetra = 2, Hexahedron = 3, Line = 4 };

struct CellInfo {
  CellType type;
  const char* name;
  int dim, nodes;
  CellType facet_type;
  int facet_nodes, num_facets;
  std::array<std::array<int, 4>, 6> facets;  // local nodes of each facet, outward orientation (3D)
  bool volume;                               // a cell type of a body mesh (not only a facet)
};

inline const std::array<CellInfo, 5>& cell_table() {
  static const std::array<CellInfo, 5> table = {{
      {CellType::Triangle, "triangle", 2, 3, CellType::Line, 2, 3, {{{0, 1}, {1, 2}, {2, 0}}}, true},
      {CellType::Quad, "quad", 2, 4, CellType::Line, 2, 4, {{{0, 1}, {1, 2}, {2, 3}, {3, 0}}}, true},
      {CellType::Tetra, "tetra", 3, 4, CellType::Triangle, 3, 4, {{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}}, true},
      {CellType::Hexahedron, "hexahedron", 3, 8, CellType::Quad, 4, 6,
       {{{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}}, true},
      {CellType::Line, "line", 1, 2, CellType::Line, 1, 2, {{{0}, {1}}}, false},
  }};
  return table;
}

inline const CellInfo& cell_info(CellType t) { return cell_table()[(int)t]; }
inline const char* cell_name(CellType t) { return cell_info(t).name; }

// A body cell type by name; anything else is an error that lists what is accepted.
inline CellType parse_cell(const std::string& s) {
  std::string known;
  for (const CellInfo& c : cell_table()) {
    if (!c.volume) continue;
    if (s == c.name) return c.type;
    known += (known.empty() ? "" : ", ") + std::string(c.name);
  }
  throw InputError("unknown cell type '" + s + "' (expected one of " + known + ")");
}

// Calls f(std::integral_constant<CellType, T>) for the body cell type t; no default branch: a
// type without an element is an error, never silently another element.
template <class F>
auto dispatch_cell(CellType t, F&& f) {
  switch (t) {
    case CellType::Triangle: return f(std::integral_constant<CellType, CellType::Triangle>{});
    case CellType::Quad: return f(std::integral_constant<CellType, CellType::Quad>{});
    case CellType::Tetra: return f(std::integral_constant<CellType, CellType::Tetra>{});
    case CellType::Hexahedron: return f(std::integral_constant<CellType, CellType::Hexahedron>{});
    case CellType::Line: break;
  }
  throw InputError(std::string("cell type '") + cell_name(t) + "' is not a body cell type");
}

}  // namespace cmg
