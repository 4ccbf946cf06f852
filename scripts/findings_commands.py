#!/usr/bin/env python3
"""Checks that every command in the findings cites only files a clean clone
has: each `kick ...`, `python3 scripts/...`, `scripts/...` or `make ...`
command in docs/findings/*.md (in code blocks and in inline code) is read
for the repository paths it names (studies/*.toml, scripts/*, docs/*,
crates/*), and each must exist in the repository (git ls-files).
Placeholders (DIR, OUT, ...) and output folders (--out, reports/) are not
files to read.

It also checks that each findings file (README.md aside) opens with its
result: a paragraph starting `**Current result` within the first lines
after the title, naming the commit (7 to 40 hex digits) of a build.

Usage: scripts/findings_commands.py [FILE ...]; exits 1 listing each
missing file with where it is cited, and each file without its opening
result."""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# A path the repository must hold: under one of these folders.
CITED = re.compile(
    r"(?<![\w./-])((?:studies|scripts|docs|crates)/[\w./-]*\w|[\w./-]+\.toml)(?![\w/-])"
)
COMMAND = re.compile(r"^\s*(?:\$\s*)?(kick|python3|scripts/|make|cargo)\b")
# Flags whose value is written, not read.
WRITTEN = re.compile(r"--(?:out|merge-out)\s+\S+")


def tracked():
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True)
    files = set(out.stdout.split())
    dirs = {str(Path(f).parent) for f in files}
    for d in list(dirs):
        parts = Path(d).parts
        dirs.update(str(Path(*parts[:k])) for k in range(1, len(parts)))
    return files | dirs


def commands(text):
    """(line number, command text) of every command in the file: each line
    of a code block, and each inline code span (which may wrap lines)."""
    found = []
    in_block = False
    prose = []
    for n, line in enumerate(text.splitlines(), 1):
        if line.strip().startswith("```"):
            in_block = not in_block
            prose.append("")
            continue
        if in_block:
            if COMMAND.match(line):
                found.append((n, line))
            prose.append("")
        else:
            prose.append(line)
    joined = "\n".join(prose)
    for m in re.finditer(r"`([^`]+)`", joined):
        code = m.group(1).replace("\n", " ")
        if COMMAND.match(code):
            found.append((joined.count("\n", 0, m.start()) + 1, code))
    return sorted(found)


# The opening result must start within this many lines after the title.
OPENING_LINES = 4
COMMIT = re.compile(r"\b[0-9a-f]{7,40}\b")


def opening_problem(text):
    """Why the file does not open with its result, or None when it does."""
    lines = text.splitlines()
    body = [n for n, line in enumerate(lines) if line.strip() and not line.startswith("# ")]
    start = next((n for n in body[:OPENING_LINES] if lines[n].startswith("**Current result")), None)
    if start is None:
        return "does not open with a `**Current result**` paragraph"
    end = next((n for n in range(start, len(lines)) if not lines[n].strip()), len(lines))
    if not COMMIT.search(" ".join(lines[start:end])):
        return "its opening result names no commit"
    return None


def main(paths):
    files = tracked()
    paths = paths or sorted(str(p) for p in (ROOT / "docs" / "findings").glob("*.md"))
    missing, unopened = [], []
    for p in paths:
        p = Path(p).resolve()
        text = p.read_text()
        for n, cmd in commands(text):
            for cited in CITED.findall(WRITTEN.sub("", cmd)):
                cited = cited.rstrip(".")
                # A placeholder the reader fills in (CASE.toml, DIR/case.toml).
                if re.search(r"(?<![a-z])[A-Z][A-Z_0-9]{2,}(?![a-z])", cited):
                    continue
                if cited not in files:
                    missing.append(f"{p.relative_to(ROOT)}:{n}: {cited}  ({cmd.strip()[:80]})")
        if p.name != "README.md" and (why := opening_problem(text)):
            unopened.append(f"{p.relative_to(ROOT)}: {why}")
    for m in missing + unopened:
        print(m)
    print(f"findings_commands: {len(missing)} cited file(s) missing from the repository")
    print(f"findings_commands: {len(unopened)} file(s) without their opening result")
    return 1 if missing or unopened else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
