"""MkDocs hook: regenerate the benchmark pages from benchmarks/results before every build."""
import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location("gen_benchmark_pages", Path(__file__).with_name("gen_benchmark_pages.py"))
_gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_gen)


def on_pre_build(config, **kwargs):
    _gen.generate()
