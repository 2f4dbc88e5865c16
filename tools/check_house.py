#!/usr/bin/env python3
"""The house rules that cannot regress silently (docs/ARCHITECTURE.md):
no host or kernel source file over 500 lines, no function over 80, and at
most MAX_REPEATED_BLOCKS blocks of code written twice (six or more
significant lines alike, in host/, kernels/ or tests/), each listed.

    python3 tools/check_house.py SOURCE_DIR
    python3 tools/check_house.py --self-test

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
MAX_REPEATED_BLOCKS = 12
BLOCK_LINES = 6


def code_files(root):
    yield from sources(root)
    for path in sorted((root / "tests").rglob("*")):
        if path.suffix in (".h", ".cpp", ".cl") and path.is_file() and "data" not in path.parts:
            yield path


def significant(path):
    """(line number, text) of the lines that carry code: not blank, not a
    comment, not braces or punctuation alone, not an include or a namespace
    (a file's preamble is alike by nature)."""
    for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        text = " ".join(line.split())
        if not text or text.startswith(("//", "/*", "*", "#include", "#pragma", "namespace", "using namespace")):
            continue
        if not any(c.isalnum() for c in text):
            continue
        yield number, text


def repeated_blocks(root):
    """Pairs of places sharing BLOCK_LINES or more significant lines in a
    row, as 'a:first-last ~ b:first-last', one per pair of runs."""
    seen = {}  # window text -> first (file, index)
    lines = {}
    pairs = {}  # (file a, file b, offset) -> [first index in a, last index in a, first index in b]
    for path in code_files(root):
        rel = str(path.relative_to(root))
        lines[rel] = list(significant(path))
        texts = [t for _, t in lines[rel]]
        for i in range(len(texts) - BLOCK_LINES + 1):
            key = "\n".join(texts[i:i + BLOCK_LINES])
            if key not in seen:
                seen[key] = (rel, i)
                continue
            other, j = seen[key]
            if other == rel and i - j < BLOCK_LINES:
                continue  # a run overlapping itself (repeated short lines)
            run = pairs.get((other, rel, i - j))
            if run and run[1] >= j - 1:
                run[1] = j
            elif not run or run[1] < j - 1:
                pairs.setdefault((other, rel, i - j), [j, j, i])
                if run:  # a second run of the same pair: its own row
                    pairs[(other, rel, i - j, j)] = [j, j, i]
    for key, (a0, a1, b0) in sorted(pairs.items()):
        a, b = key[0], key[1]
        la, lb = lines[a], lines[b]
        end_a, end_b = a1 + BLOCK_LINES - 1, b0 + (a1 - a0) + BLOCK_LINES - 1
        yield f"{a}:{la[a0][0]}-{la[end_a][0]} ~ {b}:{lb[b0][0]}-{lb[end_b][0]}"


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


def self_test():
    """The checks find what they are for: a long file and a block written
    twice, in a house made for the purpose (ctest HouseRulesRefuseABreak)."""
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        (root / "host" / "core").mkdir(parents=True)
        (root / "host" / "core" / "long.cpp").write_text("".join(f"int x{i};\n" for i in range(MAX_FILE_LINES + 1)))
        block = "".join(f"int f{i}(int a) {{ return a * {i} + {i * i}; }}\n" for i in range(BLOCK_LINES))
        (root / "host" / "core" / "one.cpp").write_text("int one;\n" + block)
        (root / "host" / "core" / "two.cpp").write_text("int two;\nint more;\n" + block)
        long_ok = any("long.cpp" in line for line in long_files(root))
        repeats = list(repeated_blocks(root))
        pair_ok = repeats == [f"host/core/one.cpp:2-{BLOCK_LINES + 1} ~ host/core/two.cpp:3-{BLOCK_LINES + 2}"]
    print(f"check_house self-test: long file found: {long_ok}; repeated blocks found: {repeats[:4]}")
    return 0 if long_ok and pair_ok else 1


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    ctags = shutil.which("ctags")
    universal = ctags and "Universal Ctags" in subprocess.run([ctags, "--version"], capture_output=True,
                                                                text=True).stdout
    broken = list(long_files(root))
    if universal:
        broken += list(long_functions(root, ctags))
    repeats = list(repeated_blocks(root))
    for r in repeats:
        print(f"repeated: {r}")
    if len(repeats) > MAX_REPEATED_BLOCKS:
        broken.append(f"{len(repeats)} blocks of code written twice (at most {MAX_REPEATED_BLOCKS}): make one serve")
    for b in broken:
        print(b)
    if broken:
        return 1
    if not universal:
        print("check_house: function lengths not checked: Universal Ctags is missing (apt-get install universal-ctags)")
        return 77
    print(f"check_house: every file within {MAX_FILE_LINES} lines, every function within {MAX_FUNCTION_LINES}, "
          f"{len(repeats)} repeated blocks (at most {MAX_REPEATED_BLOCKS})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
