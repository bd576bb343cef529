#!/usr/bin/env python3
"""Rejects C constructs in the shared kernel that OSL would not accept.

Usage: lint_subset.py KERNEL_DIR
Checks every *.h in KERNEL_DIR except the C host adaptation header
(host_c.h). See docs/kernel-subset.md for the rules. Exits 1 and prints
file:line: rule for each violation; prints a summary either way.
"""
import pathlib
import re
import sys

RULES = [
    (r"\bdouble\b", "no double (OSL has only float)"),
    (r"\b(unsigned|long|short|char|bool|enum|union|typedef|sizeof|goto|switch|case|do)\b",
     "keyword outside the kernel subset"),
    (r"\b(class|template|typename|namespace|using|new|delete|operator|auto|constexpr|"
     r"nullptr|static_cast|reinterpret_cast|const_cast)\b", "C++-only construct"),
    (r"->", "no pointers"),
    (r"(^|[(,;{])\s*(float|int|kvec3|K[A-Z]\w*)\s*\*\s*\w+\s*[,;=)\[]", "no pointer declarations"),
    (r"\(\s*(float|int|kvec3)\s*\*\s*\)", "no pointer casts"),
    (r"&\s*[A-Za-z_]\w*\s*[,)]", "no address-of / references"),
    (r"#\s*include\s*<", "no system includes in the kernel"),
    (r"\b(sqrtf|sinf|cosf|tanf|expf|logf|powf|fabsf|floorf|ceilf|atan2f|acosf|asinf|"
     r"cbrtf|fminf|fmaxf|sqrt|sin|cos|exp|log|pow|fabs|floor|ceil|atan2|acos|asin|cbrt|"
     r"fmin|fmax|isfinite|isnan)\s*\(", "call maths through the k_* macros"),
    (r"\bstd::", "no std::"),
    (r"\bstatic\b", "no static (state or qualifiers); use KNIT_FN"),
    (r"\bconst\b", "no const qualifiers (OSL has none); use KNIT_ARRAY for array params"),
    (r"[0-9]\.[0-9]*f\b|[0-9]f\b", "write float literals as KF(x)"),
    (r"\)\s*\.\s*[A-Za-z_]", "OSL cannot take a member of a call's result: assign it to a local first"),
    (r"\b(color|point|normal|vector|matrix|string|closure|output|shader|surface|volume|displacement|"
     r"illuminance|illuminate|emit|public|private|int2|float2|float3)\b", "an OSL keyword or type name"),
    (r"\)\s*\[", "OSL cannot index an expression: index a named variable"),
]

FUNC = re.compile(r"KNIT_FN\s+\w+\s+(\w+)\s*\((.*?)\)\s*\{", re.S)


def param_writes(text):
    """OSL passes parameters by reference: a kernel function must never assign
    to one. Yields (line, function, parameter) for each assignment found."""
    for m in FUNC.finditer(text):
        params = []
        for part in re.split(r",(?![^(]*\))", m.group(2)):
            part = part.strip()
            am = re.match(r"KNIT_ARRAY\(\s*\w+\s*,\s*(\w+)\s*\)", part)
            if am:
                params.append(am.group(1))
            elif part and part != "void":
                params.append(part.split()[-1])
        # Function body: match braces from the opening one.
        depth, i = 0, m.end() - 1
        while i < len(text):
            if text[i] == "{":
                depth += 1
            elif text[i] == "}":
                depth -= 1
                if depth == 0:
                    break
            i += 1
        body = text[m.end():i]
        for p in params:
            target = (r"(?:(?<![\w.])" + re.escape(p) + r"(?:\s*\[[^\]]*\])?(?:\.\w+)?"
                      r"|K[XYZ]\(\s*" + re.escape(p) + r"\s*\))")
            for w in re.finditer(target + r"\s*([-+*/]?=)(?!=)", body):
                line = text.count("\n", 0, m.end() + w.start()) + 1
                yield line, m.group(1), p

STRIP_COMMENTS = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)


def strip(text):
    # Replace comments with blanks but keep newlines so line numbers stay right.
    return STRIP_COMMENTS.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def main():
    root = pathlib.Path(sys.argv[1])
    files = sorted(p for p in root.glob("*.h") if p.name != "host_c.h")
    if not files:
        print(f"lint_subset: no kernel headers under {root}")
        return 1
    bad = 0
    for path in files:
        for lineno, line in enumerate(strip(path.read_text()).splitlines(), 1):
            if line.lstrip().startswith("#") and "include" not in line:
                continue  # preprocessor lines (macros) are host-neutral
            for pattern, why in RULES:
                if re.search(pattern, line):
                    print(f"{path}:{lineno}: {why}: {line.strip()}")
                    bad += 1
        for lineno, fn, p in param_writes(strip(path.read_text())):
            print(f"{path}:{lineno}: {fn} assigns to its parameter '{p}' "
                  "(OSL passes parameters by reference; copy it to a local)")
            bad += 1
    print(f"lint_subset: {len(files)} kernel headers, {bad} violation(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
