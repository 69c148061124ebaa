#!/usr/bin/env python3
"""The house rules a test checks (docs/processes-and-channels.md#house-rules):

  - no file over 600 lines and no function over 100 lines in the code
    (common/, processes/, experiment/, apps/, tools/, examples/, bench/,
    python/src/; tests and generated code aside);
  - each structure kept in a file (declared with visit(): the experiment's
    request, a run's outcome, the saved state) spells its keys once, in its
    declaration: no file that includes the declaration reads or writes one of
    them by hand (j["key"], .at("key"), .value("key", ...), .contains("key")).

    check_house.py [SOURCE_DIR]
    check_house.py --self-test     (each rule caught on a made-up tree)

Prints each breach with its file and line, and exits 1 if there is any.
"""
import os
import re
import sys

MAX_FILE, MAX_FUNCTION = 600, 100
CODE = ["common", "processes", "experiment", "apps", "tools", "examples", "bench", "python/src"]
SUFFIXES = (".cpp", ".hpp", ".h", ".cc")
# The structures kept in files, by the header that declares them with visit().
KEPT = ["experiment/stored/request.hpp", "experiment/stored/state_file.hpp", "experiment/plan/request.hpp",
        "experiment/execute/request.hpp", "experiment/run/driver.hpp"]


def blank(src):
    """The source with comments and string and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(src)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
        elif src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif src.startswith('R"', i) and (m := re.match(r'R"([^(\s]{0,16})\(', src[i:])):
            j = src.find(")" + m.group(1) + '"', i)
            j = n if j < 0 else j + len(m.group(1)) + 2
        elif src[i] == '"' or (src[i] == "'" and not (i > 0 and (src[i - 1].isalnum() or src[i - 1] == "_"))):
            q, j = src[i], i + 1
            while j < n and src[j] != q and src[j] != "\n":
                j += 2 if src[j] == "\\" else 1
            j = min(j + 1, n)
        else:
            out.append(src[i])
            i += 1
            continue
        out.append(re.sub(r"[^\n]", " ", src[i:j]))
        i = j
    return "".join(out)


def functions(src):
    """(first line, last line) of each function body outside another one's."""
    text, stack, start, line, found = blank(src), [], 0, 1, []
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            before = text[start:i].strip()
            if re.match(r"(inline\s+)?namespace\b|extern\b", before):
                kind = "namespace"
            elif (")" in before and "function" not in (k for k, _ in stack)
                  and not re.match(r"(struct|class|enum|union)\b", before) and not before.endswith("=")):
                kind = "function"
            else:
                kind = "block"
            stack.append((kind, line))
            start = i + 1
        elif c == "}":
            if stack:
                kind, first = stack.pop()
                if kind == "function":
                    found.append((first, line))
            start = i + 1
        elif c == ";":
            start = i + 1
    return found


def code_files(root):
    for top in CODE:
        for folder, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if name.endswith(SUFFIXES):
                    yield os.path.join(folder, name)


def sizes(root):
    breaches = []
    for path in code_files(root):
        src = open(path, encoding="utf-8", errors="replace").read()
        rel = os.path.relpath(path, root)
        lines = src.count("\n") + (0 if src.endswith("\n") or not src else 1)
        if lines > MAX_FILE:
            breaches.append(f"{rel}: {lines} lines (at most {MAX_FILE})")
        for first, last in functions(src):
            if last - first + 1 > MAX_FUNCTION:
                breaches.append(f"{rel}:{first}: a function of {last - first + 1} lines (at most {MAX_FUNCTION})")
    return breaches


def keys_spelled_twice(root):
    breaches = []
    for header in KEPT:
        src = open(os.path.join(root, header), encoding="utf-8").read()
        keys = set(re.findall(r'\bv(?:\.since|\.nullable)?\(\s*"([a-z0-9_]+)"', src))
        if not keys:
            breaches.append(f"{header}: declares no key with visit()")
            continue
        access = re.compile(r'(\[\s*"|\.(?:at|value|contains|find|erase)\(\s*")(' + "|".join(sorted(keys)) + r')"')
        for path in code_files(root):
            rel = os.path.relpath(path, root)
            if rel == header:
                continue
            text = open(path, encoding="utf-8", errors="replace").read()
            if f'"{header}"' not in text:
                continue
            for number, line in enumerate(text.split("\n"), 1):
                for m in access.finditer(line):
                    breaches.append(f'{rel}:{number}: the key "{m.group(2)}" of {header} spelled by hand')
    return breaches


def self_test():
    """Each rule is caught on a made-up tree, and a tree keeping them passes."""
    import tempfile
    with tempfile.TemporaryDirectory() as root:
        def write(rel, text):
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            open(os.path.join(root, rel), "w").write(text)
        for header in KEPT:
            write(header, 'struct S {\n  template <class V>\n  void visit(V& v) {\n    v("steps", steps);\n  }\n};\n')
        body = "".join(f"  x += {i};  // {{ not a brace\n" for i in range(97))
        write("experiment/fine.cpp", 'int f(int x) {\n  auto s = "}";\n' + body[body.index("\n") + 1:] + "  return x;\n}\n")
        assert sizes(root) == [] and keys_spelled_twice(root) == [], (sizes(root), keys_spelled_twice(root))
        write("experiment/long.cpp", "int g(int x) {\n" + body + "  x += 1;\n  return x;\n}\n")
        write("apps/big.cpp", "// a line\n" * (MAX_FILE + 1))
        write("experiment/hand.cpp", '#include "experiment/run/driver.hpp"\nint n = j["steps"];\n')
        found = sizes(root) + keys_spelled_twice(root)
        expected = ["experiment/long.cpp:1: a function of 101 lines", f"apps/big.cpp: {MAX_FILE + 1} lines",
                    'experiment/hand.cpp:2: the key "steps" of experiment/run/driver.hpp']
        missed = [e for e in expected if not any(f.startswith(e) for f in found)]
        assert not missed and len(found) == len(expected), f"missed {missed}; found {found}"
    print("each house rule is caught")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    breaches = sizes(root) + keys_spelled_twice(root)
    for b in breaches:
        print(b)
    print(f"{len(breaches)} breach(es) of the house rules" if breaches else "the house rules hold")
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())
