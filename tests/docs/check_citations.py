#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Every citation of a project document in the code points at something that exists.

Finds each citation of a `.md` document in the sources (*.cpp, *.h, *.inc, *.py, *.sh,
CMakeLists.txt) and what follows it:

    design.md §3                  a numbered section: a heading "## 3. ..." (or "### 3.1 ...")
    docs/perspective.md §2-4      a range: both ends must exist
    docs/perspective.md eq. 10.1  an equation label "(10.1)" in the document
    docs/scenes.md "Composition"  a heading, or a paragraph title **Composition.**, that starts
                                  with the quoted words (backticks and case ignored)

A bare name (design.md) is looked for in docs/, then at the root; a path (bench/README.md) is
taken from the root. Prints one line per broken citation, `file:line: what is missing`, and
exits 1 when there is any (docs/contributing.md "Citations").

Usage: check_citations.py [ROOT] [FILE...]   (FILEs: check only these, for the self-test)
"""
import pathlib
import re
import subprocess
import sys

# This check and its self-test quote bogus citations on purpose (tests/docs/test_citations.sh).
SELF_TEST = "tests/docs/"
SOURCE_PATTERNS = ["*.cpp", "*.h", "*.inc", "*.py", "*.sh", "*CMakeLists.txt", "*.md"]

# A document name not preceded by a path character (so "$out/gallery.md", a file a script
# writes, is not a citation), optionally under docs/ or bench/.
CITATION = re.compile(
    r"(?<![\w$/.\-])((?:docs/|bench/)?[\w\-]+\.md)\b"
    r"(?P<tail>(?:'s)?[ \t]*(?:"
    r"§\s?(?P<sec>\d+(?:\.\d+)*(?:\s?[-–]\s?\d+(?:\.\d+)*)?)"
    r"|eq\.\s?(?P<eq>\d+(?:\.\d+)*)"
    r"|\"(?P<name>[^\"\n]+)\""
    r"))?")


def tracked_sources(root, only):
    if only:
        return [pathlib.Path(f) for f in only]
    listed = subprocess.run(["git", "-C", str(root), "ls-files", "--", *SOURCE_PATTERNS],
                            capture_output=True, text=True)
    if listed.returncode == 0:
        return [root / f for f in listed.stdout.split() if not f.startswith(SELF_TEST)]
    # Not a git checkout (a source archive): every matching file but the build trees'.
    return sorted(p for pattern in SOURCE_PATTERNS for p in root.rglob(pattern)
                  if not any(part.startswith("build") or part.startswith(".")
                             for part in p.relative_to(root).parts[:-1])
                  and not p.relative_to(root).as_posix().startswith(SELF_TEST))


def resolve(root, name):
    candidates = [root / name] if "/" in name else [root / "docs" / name, root / name]
    for path in candidates:
        if path.is_file():
            return path
    return None


def normalise(text):
    return re.sub(r"\s+", " ", text.replace("`", "").replace("*", "")).strip().lower()


class Document:
    def __init__(self, path):
        self.text = path.read_text(encoding="utf-8")
        in_code = False
        self.headings = []
        for line in self.text.splitlines():
            if line.startswith("```"):
                in_code = not in_code
            elif not in_code and re.match(r"#{1,6}\s", line):
                self.headings.append(normalise(line.lstrip("#")))
        # Paragraph titles: **Slices.** or **Slices in perspective.**
        self.titles = [normalise(t) for t in re.findall(r"^\*\*([^*\n]+?)\.?\*\*", self.text,
                                                        re.MULTILINE)]

    def has_section(self, number):
        return any(re.match(re.escape(number) + r"(\.|\s|$)", h) for h in self.headings)

    def has_equation(self, label):
        return re.search(r"\(" + re.escape(label) + r"\)", self.text) is not None

    def has_name(self, name):
        wanted = normalise(name)
        return any(h.startswith(wanted) for h in self.headings + self.titles)


def check_citation(doc, match):
    """What is missing for one citation, or None."""
    if match.group("sec"):
        ends = re.split(r"\s?[-–]\s?", match.group("sec"))
        missing = [e for e in ends if not doc.has_section(e)]
        return "no section §" + ", §".join(missing) if missing else None
    if match.group("eq"):
        label = match.group("eq")
        return None if doc.has_equation(label) else "no equation (" + label + ")"
    if match.group("name"):
        name = match.group("name")
        return None if doc.has_name(name) else 'no section or paragraph "' + name + '"'
    return None


def main(argv):
    root = pathlib.Path(argv[1] if len(argv) > 1 else ".").resolve()
    documents = {}
    problems = []
    count = 0
    for source in tracked_sources(root, argv[2:]):
        try:
            lines = source.read_text(encoding="utf-8", errors="replace").splitlines()
        except OSError:
            continue
        for number, line in enumerate(lines, 1):
            for match in CITATION.finditer(line):
                count += 1
                name = match.group(1)
                where = f"{source.relative_to(root) if source.is_relative_to(root) else source}:{number}"
                path = resolve(root, name)
                if path is None:
                    problems.append(f"{where}: {name}: no such document")
                    continue
                doc = documents.setdefault(path, Document(path))
                missing = check_citation(doc, match)
                if missing:
                    problems.append(f"{where}: {name}: {missing}")
    for problem in problems:
        print(problem)
    print(f"{count} citations checked, {len(problems)} broken")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
