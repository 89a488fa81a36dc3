#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The include graph against the documented layering (docs/design.md §2 "Levels", "Facades").

Reads every #include "folder/..." of the libraries' sources and checks that
  1. each library uses exactly the libraries docs/design.md's table says it uses (a use the table
     does not list is an upward or sideways include; a listed use the code no longer has is a
     stale table);
  2. another folder includes only a library's facade or a header the facade lists: never a
     header of detail/, never a header the facade does not name (the facade is the API, and
     `cmake --install` installs exactly the facade and its list, cmake/ImpulseInstall.cmake);
  3. every header at a library's top level is listed in its facade (anything else goes in detail/);
  4. no header the facade lists includes the facade back, or a detail/ header (it is installed,
     and detail/ is not).
Prints one line per violation and exits 1 if there is any.
  check_layering.py SOURCE_DIR
"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/([^"]+)"', re.M)


def levels_table():
    """{library: set of libraries it uses} from docs/design.md §2's table."""
    text = (root / "docs/design.md").read_text()
    section = text[text.index("**Levels.**"):text.index("**Facades.**")]
    uses = {}
    for row in re.finditer(r"^\| (\d+) \| ([a-z]+) \| ([^|]*)\|", section, re.M):
        lib, used = row.group(2), row.group(3).strip()
        uses[lib] = set() if used in ("—", "-", "") else {u.strip() for u in used.split(",")}
    if not uses:
        sys.exit("docs/design.md §2: no '| level | library | uses |' rows found")
    return uses


def sources(folder):
    for p in sorted((root / folder).rglob("*")):
        if p.suffix in (".h", ".cpp", ".inc") or p.name.endswith(".cpp.in"):
            yield p


def facade_lists(libraries):
    """{library: the headers its facade lists}, each facade read once."""
    lists = {}
    for lib in libraries:
        facade = root / lib / f"{lib}.h"
        lists[lib] = ({f"{a}/{b}" for a, b in INCLUDE.findall(facade.read_text())}
                      if facade.exists() else set())
    return lists


def main():
    table = levels_table()
    libraries = [lib for lib in table if lib not in ("app", "python")]
    listed_by = facade_lists(libraries)
    errors = []
    used = {lib: set() for lib in table}
    for folder in table:
        for path in sources(folder):
            rel = path.relative_to(root).as_posix()
            for target, rest in INCLUDE.findall(path.read_text(errors="replace")):
                if target == folder or target not in table:
                    continue
                used[folder].add(target)
                header = f"{target}/{rest}"
                if target in ("app", "python"):
                    errors.append(f"{rel}: includes {header}: app/ and python/ are programs, not libraries")
                elif "detail/" in rest:
                    errors.append(f"{rel}: includes {header}, internal to {target}/ (its detail/)")
                elif header != f"{target}/{target}.h" and header not in listed_by[target]:
                    errors.append(f"{rel}: includes {header}, which {target}/{target}.h does not list")
    for lib, expected in table.items():
        for extra in sorted(used[lib] - expected):
            errors.append(f"{lib}/ uses {extra}/, which docs/design.md §2 does not allow it")
        for stale in sorted(expected - used[lib]):
            errors.append(f"docs/design.md §2 says {lib}/ uses {stale}/, but nothing of {lib}/ includes it")
    for lib in libraries:
        listed = listed_by[lib]
        if not listed:
            errors.append(f"{lib}/{lib}.h: missing, or lists no header")
        for header in sorted((root / lib).glob("*.h")):
            name = f"{lib}/{header.name}"
            if name != f"{lib}/{lib}.h" and name not in listed:
                errors.append(f"{name}: at {lib}/'s top level but not listed in {lib}/{lib}.h (move it to {lib}/detail/)")
        for name in sorted(listed):
            if not name.startswith(f"{lib}/"):
                continue
            text = (root / name).read_text()
            if f'"{lib}/{lib}.h"' in text:
                errors.append(f"{name}: listed in {lib}/{lib}.h and includes it back")
            for target, rest in INCLUDE.findall(text):
                if rest.startswith("detail/"):
                    errors.append(f"{name}: public (listed in {lib}/{lib}.h) but includes {target}/{rest}")
    for e in errors:
        print(e)
    print(f"layering: {sum(len(u) for u in used.values())} library uses, "
          f"{len(libraries)} facades checked, {len(errors)} problems")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
