#!/usr/bin/env python3
"""No function over 80 lines (issue 43): a longer one is split into named steps. Fails, naming the file, the line
and the function, for any function body in src/**/*.{h,cpp} longer than MAX_LINES, counted from the line of the
body's opening brace to the line of its closing brace, inclusive. Lambdas and local classes inside a function count
toward it; a lambda at namespace scope counts as a function of its own.

The scanner is a lexer, not a parser: comments, string and character literals (with their u8/u/U/L prefixes), raw
strings (R"delim(...)delim") and preprocessor lines are blanked first, keeping the lines, and digit separators
(1'000) are not taken for character literals; then each brace outside a function is classified by the text since
the last `;`, `{` or `}` (its head): a namespace, class, struct, union, enum, concept or `extern "C"` opens a scope,
an initializer (`= {`, `T x{...}`, a member initializer of a constructor) is skipped, and a head with a parameter
list opens a function. A file whose braces do not balance fails the check too.

usage: check_function_size.py [SRC_DIR]     (default: the src/ beside this script's tests/)
       check_function_size.py --self-test
"""
import pathlib
import re
import sys

MAX_LINES = 80
IDENT = re.compile(r"[A-Za-z_]\w*$")
SCOPE_KEYWORD = re.compile(r"\b(namespace|class|struct|union|enum|concept|extern)\b")
RAW_PREFIXES = ("R", "u8R", "uR", "UR", "LR")


def blank_block_comment(text, i, out):
    """The /* ... */ comment at `i` appended to `out` as spaces (its newlines kept); returns the index after it."""
    end = text.find("*/", i + 2)
    end = len(text) if end < 0 else end + 2
    out.append(re.sub(r"[^\n]", " ", text[i:end]))
    return end


def blank(text):
    """`text` with comments, literals and preprocessor lines replaced by spaces; newlines (and so line numbers)
    are kept. Literals become "" or '' so that a head still reads as an expression."""
    out = []
    i, n = 0, len(text)
    line_start = True  # only whitespace since the last newline (a `#` there starts a preprocessor line)
    while i < n:
        c = text[i]
        if c == "\n":
            out.append(c)
            i += 1
            line_start = True
            continue
        if line_start and c == "#":
            # A preprocessor line, with its backslash continuations; comments inside it are blanked with it.
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                if text.startswith("/*", i):
                    i = blank_block_comment(text, i, out)
                    continue
                out.append(" ")
                i += 1
            continue
        if not c.isspace():
            line_start = False
        if text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
            out.append(" " * (end - i))
            i = end
            continue
        if text.startswith("/*", i):
            i = blank_block_comment(text, i, out)
            continue
        if c == '"':
            token = re.search(r"[A-Za-z_0-9]*$", "".join(out[-8:]) if out else "").group(0)
            if token in RAW_PREFIXES:
                m = re.compile(r'"([^()\\\s]{0,16})\(').match(text, i)
                if m:
                    close = ")" + m.group(1) + '"'
                    end = text.find(close, m.end())
                    end = n if end < 0 else end + len(close)
                    out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:end - 1]) + '"')
                    i = end
                    continue
            end = skip_quoted(text, i, '"')
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:end - 1]) + '"')
            i = end
            continue
        if c == "'":
            # A digit separator when it is inside a number (the token before it starts with a digit).
            token = re.search(r"[A-Za-z_0-9.']*$", "".join(out[-64:]) if out else "").group(0)
            if token and (token[0].isdigit() or (token[0] == "." and len(token) > 1 and token[1].isdigit())):
                out.append(c)
                i += 1
                continue
            end = skip_quoted(text, i, "'")
            out.append("'" + re.sub(r"[^\n]", " ", text[i + 1:end - 1]) + "'")
            i = end
            continue
        out.append(c)
        i += 1
    return "".join(out)


def skip_quoted(text, i, quote):
    """The index just past the literal that opens with `quote` at i (escapes skipped; stops at a newline)."""
    j = i + 1
    while j < len(text):
        if text[j] == "\\":
            j += 2
            continue
        if text[j] == quote or text[j] == "\n":
            return j + 1
        j += 1
    return len(text)


def top_level(head):
    """`head` with everything inside () and [] removed, and whether a bracket is still open."""
    out, depth = [], 0
    for ch in head:
        if ch in "([":
            if depth == 0:
                out.append(ch)
            depth += 1
        elif ch in ")]":
            depth = max(depth - 1, 0)
            if depth == 0:
                out.append(ch)
        elif depth == 0:
            out.append(ch)
    return "".join(out), depth > 0


def function_name(head):
    """The name before the head's parameter list: `ns::Type::method`, `operator()`, `~Type`, or `lambda`."""
    flat = " ".join(head.split())
    m = re.search(r"((?:[\w~]+\s*::\s*)*(?:operator\s*(?:\(\)|\[\]|[^\s(]+)|~?\w+))\s*(?:<[^()]*>)?\s*\(", flat)
    if not m:
        return "lambda"
    name = re.sub(r"operator\s+(?=\w)", "operator ", m.group(1))
    name = re.sub(r"\s+(?!\w)|(?<!operator)\s+", "", name)
    if name in ("if", "for", "while", "switch", "return", "sizeof", "decltype", "noexcept", "requires", "alignas"):
        return "lambda"
    return name


def classify(head, stack):
    """What a `{` opens outside a function: 'fn', 'scope' (namespace, class, extern "C") or 'init'."""
    flat, open_bracket = top_level(head)
    stripped = flat.strip()
    if open_bracket:
        # Inside (...) or [...] of a namespace-scope expression: a lambda's body, or a braced initializer.
        tail = head[max(head.rfind("("), head.rfind(","), head.rfind("[") - 1) + 1:]
        return "fn" if re.search(r"\[[^\[\]]*\]\s*(\([^()]*\))?[\w\s:<>&*,\->]*$", tail) else "init"
    before_params = flat.split("(")[0]
    while re.search(r"<[^<>]*>", before_params):
        before_params = re.sub(r"<[^<>]*>", "", before_params)
    if SCOPE_KEYWORD.search(before_params):
        return "scope"
    if "(" not in flat:
        return "init"  # T x{...}, a default member initializer, `= {`
    last_paren = flat.rfind(")")
    if "=" in flat[last_paren:].replace("==", "").replace("->", "") or stripped.endswith("="):
        return "init"
    # A constructor's member initializer: `X() : a_{1}, b_{2} {` — the body's brace follows `)` or `}`, an
    # initializer's brace follows a name.
    after = flat[flat.find(")") + 1:]
    if re.search(r"(?<!:):(?!:)", after) and re.search(r"[\w>]\s*$", stripped) and not re.search(
            r"\b(const|noexcept|override|final|mutable)\s*$", stripped) and "->" not in after:
        return "init"
    return "fn"


def scan(text):
    """(name, first line, last line) of each function body in `text`; raises ValueError on unbalanced braces."""
    code = blank(text)
    found = []
    stack = []  # (kind, line, name, class name) of each open brace
    head = []
    line = 1
    in_fn = 0
    for ch in code:
        if ch == "\n":
            line += 1
            head.append(" ")
            continue
        if in_fn:
            if ch == "{":
                stack.append(("blk", line, None))
            elif ch == "}":
                kind, start, name = stack.pop()
                if kind == "fn":
                    in_fn -= 1
                    found.append((name, start, line))
                    head = []
            continue
        if ch == "{":
            h = "".join(head)
            kind = classify(h, stack)
            if kind == "fn":
                name = function_name(h)
                classes = [n for k, _, n in stack if k == "scope" and n]
                if "::" not in name and classes and name != "lambda":
                    name = classes[-1] + "::" + name
                stack.append(("fn", line, name))
                in_fn = 1
            elif kind == "scope":
                names = re.findall(r"\b(?:class|struct|union)\s+(?:\[\[[^\]]*\]\]\s*)?(\w+)", h)
                stack.append(("scope", line, names[-1] if names else None))
                head = []
            else:
                stack.append(("init", line, None))
                head.append(ch)
            continue
        if ch == "}":
            if not stack:
                raise ValueError(f"line {line}: a '}}' without its '{{'")
            kind, _, _ = stack.pop()
            if kind == "init":
                head.append(ch)
            else:
                head = []
            continue
        if ch == ";" and not (stack and stack[-1][0] == "init"):
            head = []
            continue
        head.append(ch)
    if stack:
        raise ValueError(f"line {stack[-1][1]}: a '{{' without its '}}'")
    return found


def main():
    src = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[2] / "src"
    problems = []
    files = functions = longest = 0
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".h", ".cpp") or not path.is_file():
            continue
        files += 1
        rel = path.relative_to(src.parent)
        try:
            found = scan(path.read_text(encoding="utf-8"))
        except ValueError as e:
            problems.append(f"{rel}:{e}: the braces do not balance, so the function sizes are unknown")
            continue
        for name, start, end in found:
            functions += 1
            size = end - start + 1
            longest = max(longest, size)
            if size > MAX_LINES:
                problems.append(f"{rel}:{start}: {name} is {size} lines (at most {MAX_LINES}): split it into named "
                                f"steps")
    for p in problems:
        print("FAIL", p)
    print(f"check_function_size: {functions} functions in {files} files, the longest {longest} lines "
          f"(at most {MAX_LINES}), {len(problems)} problems")
    return 1 if problems else 0


def main_on(src):
    sys.argv = [sys.argv[0], str(src)]
    return main()


def body(lines, name="planted"):
    """A function whose body spans `lines` lines, braces included, with the things that could fool a lexer."""
    filler = [
        '  const char* s = "}}} { // not a comment";',
        "  const char c = '}';",
        "  const char d = '\\'';",
        "  /* } a comment with a brace { */",
        "  // } a line comment",
        '  const char* r = R"x(a raw ")" string } with braces {)x";',
        "  const long big = 1'000'000;",
        "  auto f = [&](int v) { return v + 1; };",
        "  if (big > 0) { (void)f(1); }",
    ]
    inner = [filler[i % len(filler)] for i in range(lines - 2)]
    return [f"int {name}() {{"] + inner + ["}"]


def self_test():
    """The check can fail: a copy of src/ with an 81-line function planted fails, naming it, and one with an
    80-line function passes; literals, comments and raw strings with braces do not confuse the scanner."""
    import shutil
    import subprocess
    import tempfile
    src = pathlib.Path(__file__).resolve().parents[2] / "src"
    results = []
    results.append((main_on(src) == 0, "src/ as it is passes"))
    sample = "\n".join(["namespace a {", "struct S {", "  S() : x_{1}, y_(2) {", "  }", "  int x_{0}, y_;",
                        "  int get() const { return x_; }", "};", "}  // namespace a"] + body(5, "five") +
                       ["const int kTable[] = {1, 2, 3};", 'extern "C" {', "int g() {", "  return 0;", "}", "}"])
    got = [(n, e - s + 1) for n, s, e in scan(sample)]
    want = [("S::S", 2), ("S::get", 1), ("five", 5), ("g", 3)]
    results.append((got == want, f"the scanner finds constructors, members, literals and extern \"C\" ({got})"))
    with tempfile.TemporaryDirectory() as tmp:
        copy = pathlib.Path(tmp) / "src"
        shutil.copytree(src, copy)
        planted = copy / "core" / "planted_size_test.cpp"
        planted.write_text("namespace ff {\n" + "\n".join(body(80, "fits")) + "\n}\n", encoding="utf-8")
        fits = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        results.append(("planted_size_test" not in fits.stdout and (fits.returncode == 0) == results[0][0],
                        "a planted 80-line function passes"))
        planted.write_text("namespace ff {\n" + "\n".join(body(81, "too_long")) + "\n}\n", encoding="utf-8")
        long = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        caught = long.returncode != 0 and "src/core/planted_size_test.cpp:2: too_long is 81 lines" in long.stdout
        results.append((caught, "a planted 81-line function fails the check, named with its file and line"))
        planted.write_text("namespace ff {\nint broken() {\n", encoding="utf-8")
        broken = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        results.append((broken.returncode != 0 and "do not balance" in broken.stdout,
                        "a file whose braces do not balance fails the check"))
    for ok, what in results:
        print(f"{'ok  ' if ok else 'FAIL'} {what}")
    return 0 if all(ok for ok, _ in results) else 1


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--self-test":
        sys.exit(self_test())
    sys.exit(main())
