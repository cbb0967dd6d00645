#!/usr/bin/env python3
"""Checks the include layering of src/ (docs/ARCHITECTURE.md, the folder diagram).

Every folder of the library has a level; a file may include its own folder and the folders
of lower levels only, so there is no upward include and no cycle between folders. Folders of
one level (solver, lp, analysis; probe, ensemble) do not include each other. Exits with 1 and
lists every include that breaks this.

usage: check_layers.py [SOURCE_DIR]   (default: the repository of this script)
"""
import pathlib
import re
import sys

# Level of each folder: src/unjam/<folder>, then src/cli and src/python over the library.
LEVELS = {
    "core": 0,
    "packing": 1,
    "contact": 2,
    "solver": 3, "lp": 3, "analysis": 3,
    "protocol": 4,
    "probe": 5, "ensemble": 5,
    "campaign": 6,
    "cli": 7, "python": 7,
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"(?:unjam/)?([a-z_]+)/[^"]+"', re.M)


def folder_of(path, src):
    parts = path.relative_to(src).parts
    return parts[1] if parts[0] == "unjam" else parts[0]


def main():
    root = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent
    src = root / "src"
    errors = []
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".hpp", ".cpp", ".in"):
            continue
        own = folder_of(path, src)
        if own not in LEVELS:
            errors.append(f"{path.relative_to(root)}: folder {own} has no level in {__file__}")
            continue
        for used in INCLUDE.findall(path.read_text()):
            if used == own or used not in LEVELS:
                continue
            if LEVELS[used] >= LEVELS[own]:
                errors.append(f"{path.relative_to(root)}: {own} (level {LEVELS[own]}) includes "
                              f"{used} (level {LEVELS[used]})")
    for e in errors:
        print(e)
    if not errors:
        print(f"include layering of {src}: ok")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
