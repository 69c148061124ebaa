"""A component written in Python as a process on the bus.

    python3 -m afford.process motivation MODULE:CLASS [--lcm-url URL] [--bus-key FILE] [--log-level L]
    python3 -m afford.process predictors MODULE:CLASS [... --checkpoint-dir DIR]

MODULE is an importable module (the current folder is on the path) or a
file (path/to/mine.py). The class is registered under its kind
(afford.components.kind_of) and the shipped node runs it (a motivation, or
the predictors with the class as their affordance predictor): the edge, the
input rules, STATUS, live restart and Ctrl-C are the C++ ones, so no
protocol code is written in Python. A run uses it when its motivation.kind
(predictors.affordance.kind) is that kind, e.g.

    afford experiment base --set motivation.kind=mine \\
        --process motivation='/usr/bin/python3 -m afford.process motivation mine.py:Mine'
"""
from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path

from . import _afford
from .components import ROLES

USAGE = "usage: python3 -m afford.process motivation|goals|predictors MODULE:CLASS [--lcm-url URL] [--bus-key FILE] [...]"


def load_class(target: str):
    module_name, sep, name = target.rpartition(":")
    if not sep or not module_name or not name:
        raise SystemExit(f"afford.process: '{target}' is not MODULE:CLASS\n{USAGE}")
    if module_name.endswith(".py"):
        path = Path(module_name)
        if not path.is_file():
            raise SystemExit(f"afford.process: no file {path}")
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[path.stem] = module
        spec.loader.exec_module(module)
    else:
        if "" not in sys.path:
            sys.path.insert(0, "")
        module = importlib.import_module(module_name)
    try:
        return getattr(module, name)
    except AttributeError:
        raise SystemExit(f"afford.process: module {module_name} has no {name}") from None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv == ["--version"]:
        print(f"afford.process {_afford.version}")
        return 0
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(USAGE, file=sys.stderr)
        return 2
    if argv[0] not in ROLES:
        print(f"afford.process: '{argv[0]}': a component in Python stands in for the motivation, the goal "
              f"chooser (goals: the motivation process of the goals phase) or the predictors\n{USAGE}", file=sys.stderr)
        return 2
    ROLES[argv[0]][1](load_class(argv[1]))
    return _afford.serve(argv[0], [f"afford-{argv[0]} ({argv[1]})", *argv[2:]])


if __name__ == "__main__":
    sys.exit(main())
