#!/usr/bin/env python3
"""The house rules that cannot regress silently (docs/ARCHITECTURE.md):
no host or kernel source file over 500 lines, no function over 80.

    python3 tools/check_house.py SOURCE_DIR

Functions are found by Universal Ctags (Debian's universal-ctags, which
tools/setup.sh installs); kernels are read as C. Exits 0 when the rules
hold, 1 naming every file and function that breaks them, 77 (a skip for
ctest) when Universal Ctags is missing."""
import json
import pathlib
import shutil
import subprocess
import sys

MAX_FILE_LINES = 500
MAX_FUNCTION_LINES = 80


def sources(root):
    for folder, endings in (("host", (".h", ".cpp")), ("kernels", (".h", ".cl"))):
        for path in sorted((root / folder).rglob("*")):
            if path.suffix in endings and path.is_file():
                yield path


def long_files(root):
    for path in sources(root):
        lines = path.read_text(encoding="utf-8", errors="replace").count("\n")
        if lines > MAX_FILE_LINES:
            yield f"{path.relative_to(root)}: {lines} lines (at most {MAX_FILE_LINES})"


def long_functions(root, ctags):
    files = [str(p) for p in sources(root)]
    out = subprocess.run([ctags, "--langmap=C:+.cl", "--fields=+ne", "--output-format=json", "-f", "-"] + files,
                         capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        tag = json.loads(line)
        if tag.get("kind") not in ("function", "method") or "end" not in tag:
            continue
        length = tag["end"] - tag["line"] + 1
        if length > MAX_FUNCTION_LINES:
            rel = pathlib.Path(tag["path"]).relative_to(root)
            yield f"{rel}:{tag['line']}: {tag['name']} is {length} lines (at most {MAX_FUNCTION_LINES})"


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    ctags = shutil.which("ctags")
    universal = ctags and "Universal Ctags" in subprocess.run([ctags, "--version"], capture_output=True,
                                                                text=True).stdout
    broken = list(long_files(root))
    if universal:
        broken += list(long_functions(root, ctags))
    for b in broken:
        print(b)
    if broken:
        return 1
    if not universal:
        print("check_house: function lengths not checked: Universal Ctags is missing (apt-get install universal-ctags)")
        return 77
    print("check_house: every file within 500 lines, every function within 80")
    return 0


if __name__ == "__main__":
    sys.exit(main())
