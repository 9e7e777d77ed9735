#!/usr/bin/env python3
"""Type stubs for the hapticfield Python module, from the built module's own signatures and docstrings.

    PYTHONPATH=build/python python3 scripts/make_stubs.py           # rewrite python/stubs/hapticfield/__init__.pyi
    PYTHONPATH=build/python python3 scripts/make_stubs.py --check   # exit 1 when the committed stubs are stale
    python3 scripts/make_stubs.py --out DIR                         # write DIR/hapticfield/__init__.pyi instead

pybind11 puts each function's signature on the first line of its docstring ("name(a: int = 1) -> float"),
one per overload; this script turns those into Python stub syntax (defaults that are not plain literals as
`...`) and checks every line it writes with Python's own parser. The output depends only on the module's
bindings: names are sorted. An argument is typed as what pybind11 converts at run time, a result as what it
returns (see ARGUMENTS); bare dict, list, tuple and ndarray get their parameters (mypy --strict asks for them).
"""
import argparse
import ast
import difflib
import importlib
import inspect
import pathlib
import re
import sys

MODULE = "hapticfield"
HERE = pathlib.Path(__file__).resolve().parent
STUB = HERE.parent / "python" / "stubs" / MODULE / "__init__.pyi"
HEADER = f'''# Type stubs of the {MODULE} module, generated from its bindings by scripts/make_stubs.py:
# do not edit. Regenerate after changing python/src (see python/README.md):
#   PYTHONPATH=build/python python3 scripts/make_stubs.py
'''
IMPORTS = """import os
import typing
from typing import (Any, Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Set, SupportsFloat, Tuple,
                    Union, overload)

import numpy
import numpy.typing

# A vector argument of 2 or 3 numbers: pybind11 converts any sequence of that length whose items have
# __float__ (a list, a tuple, numpy scalars) or a 1-D numpy array of floats or integers; another length
# raises TypeError. Results are lists.
_Vec2 = Union[Sequence[SupportsFloat], numpy.typing.NDArray[Union[numpy.floating[Any], numpy.integer[Any]]]]
_Vec3 = Union[Sequence[SupportsFloat], numpy.typing.NDArray[Union[numpy.floating[Any], numpy.integer[Any]]]]
"""
# pybind11 type names that are not Python's.
NAMES = {"buffer": "Any", "capsule": "Any", "handle": "Any", "iterator": "Iterator[Any]", "function": "Callable[..., Any]",
         "iterable": "Iterable[Any]", "sequence": "Sequence[Any]", "none": "None", "json": "Any",
         "dict": "Dict[str, Any]", "list": "List[Any]", "tuple": "Tuple[Any, ...]"}
# How pybind11 converts an argument, by the type its signature names (pybind11/stl.h, numpy.h): a std::array of N
# from any sequence of N numbers, a std::vector from any sequence but str and bytes (List[T] -> Sequence[T]), a
# py::array_t from anything numpy.asarray takes. A plain py::array takes a numpy array only.
ARGUMENTS = [(r"List\[float\[2\]\]", "_Vec2"), (r"List\[float\[3\]\]", "_Vec3"),
             (r"numpy\.ndarray\[[A-Za-z0-9_.]+(\[[^\]]*\])?\]", "numpy.typing.ArrayLike"),
             (r"\bList\[", "Sequence[")]
LITERAL = re.compile(r"^(None|True|False|-?\d+(\.\d*)?([eE][-+]?\d+)?|-?inf|nan|'[^'\\]*'|\"[^\"\\]*\")$")


def split_top(text, sep=","):
    """`text` split at `sep` outside brackets and quotes."""
    parts, depth, quote, start = [], 0, None, 0
    for i, c in enumerate(text):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c in "([{<":
            depth += 1
        elif c in ")]}>":
            depth -= 1
        elif c == sep and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts if p.strip()]


def clean_type(t, argument=False):
    """A pybind11 type name in stub syntax: as an argument (what pybind11 converts) or as a result."""
    t = t.replace(f"{MODULE}.", "")
    if argument:
        for pattern, replacement in ARGUMENTS:
            t = re.sub(pattern, replacement, t)
    t = re.sub(r"numpy\.ndarray\[([A-Za-z0-9_.]+)(\[[^\]]*\])?\]", r"numpy.typing.NDArray[\1]", t)
    t = re.sub(r"numpy\.ndarray\b(?!\[)", "numpy.typing.NDArray[Any]", t)
    while re.search(r"\[\d+\]", t):
        t = re.sub(r"\[\d+\]", "", t)
    t = re.sub(r"\b[A-Za-z_][A-Za-z0-9_]*\b", lambda m: NAMES.get(m.group(0), m.group(0)), t)
    return t


def clean_parameter(p, first):
    if p in ("*", "/") or p.startswith("*"):
        name, _, annotation = p.partition(":")
        return f"{name.strip()}: {clean_type(annotation.strip(), argument=True)}" if annotation else p
    head, eq, default = p.partition("=")
    name, colon, annotation = head.partition(":")
    name = name.strip()
    if first and name == "self":
        return "self"
    annotation = clean_type(annotation.strip(), argument=True) if colon else ""
    default = default.strip()
    if eq and default == "None" and annotation and not annotation.startswith(("Optional[", "None", "Any")):
        annotation = f"Optional[{annotation}]"  # pybind11 allows None where the C++ side takes a holder or pointer
    out = name + (f": {annotation}" if annotation else "")
    if eq:
        out += " = " + (default if LITERAL.match(default) and default not in ("inf", "-inf", "nan") else "...")
    return out


def parse_signature(line, name):
    """'name(params) -> ret' as (params, ret) in stub syntax, or None when the line is not a signature."""
    m = re.match(re.escape(name) + r"\((.*)\)(?:\s*->\s*(.+))?$", line.strip())
    if not m:
        return None
    params = [clean_parameter(p, i == 0) for i, p in enumerate(split_top(m.group(1)))]
    return ", ".join(params), clean_type(m.group(2) or "None")


def signatures(obj, name):
    """[(params, ret, doc)] for each overload of a pybind11 function."""
    doc = inspect.getdoc(obj) or ""
    lines = doc.split("\n")
    if len(lines) > 1 and lines[1].strip() == "Overloaded function.":
        out = []
        for block in re.split(r"\n\d+\. (?=" + re.escape(name) + r"\()", "\n" + "\n".join(lines[2:]))[1:]:
            first, _, rest = block.partition("\n")
            sig = parse_signature(first, name)
            if sig:
                out.append((*sig, rest.strip()))
        if out:
            return out
    sig = parse_signature(lines[0], name) if lines else None
    if sig:
        return [(*sig, "\n".join(lines[1:]).strip())]
    return [("*args: Any, **kwargs: Any", "Any", doc.strip())]


def docstring(text, indent):
    if not text:
        return ""
    text = text.replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    body = "\n".join((indent + line) if line else "" for line in text.split("\n"))
    return f'{indent}"""{body[len(indent):]}"""\n'


def checked(source, fallback):
    """`source` when Python parses it, `fallback` (said on stderr) otherwise."""
    try:
        ast.parse(source.strip() if not source.startswith(" ") else "class _:\n" + source)
        return source
    except SyntaxError:
        print(f"make_stubs: kept a generic signature for: {source.splitlines()[0].strip()}", file=sys.stderr)
        return fallback


def function(obj, name, indent="", method=False):
    overloads = signatures(obj, name)
    out = []
    for params, ret, doc in overloads:
        deco = f"{indent}@overload\n" if len(overloads) > 1 else ""
        head = f"{indent}def {name}({params}) -> {ret}:"
        body = docstring(doc, indent + "    ")
        generic = ("self, " if method else "") + "*args: Any, **kwargs: Any"
        text = deco + head + ("\n" + body if body else " ...\n")
        fallback = deco + f"{indent}def {name}({generic}) -> Any:" + ("\n" + body if body else " ...\n")
        out.append(checked(text, fallback))
    return "".join(out)


def is_routine(v):
    return callable(v) and (inspect.isbuiltin(v) or inspect.isroutine(v) or type(v).__name__ == "instancemethod")


def klass(cls, name):
    bases = [b for b in cls.__bases__ if b is not object and b.__name__ != "pybind11_object"]
    base_names = ", ".join((b.__name__ if b.__module__ == MODULE else f"{b.__module__}.{b.__name__}").replace(
        "builtins.", "") for b in bases)
    out = [f"class {name}({base_names}):\n" if base_names else f"class {name}:\n"]
    body = []
    doc = cls.__doc__ if "__doc__" in vars(cls) else None
    if doc and not issubclass(cls, BaseException):
        body.append(docstring(inspect.cleandoc(doc), "    "))
    members = getattr(cls, "__members__", None)
    if isinstance(members, dict):  # a pybind11 enum
        for member in members:
            body.append(f"    {member}: typing.ClassVar[{name}]\n")
    for attr, value in sorted(vars(cls).items()):
        if attr in ("__doc__", "__module__", "__dict__", "__weakref__", "__members__", "__entries"):
            continue
        if isinstance(value, property):
            _, ret, pdoc = signatures(value.fget, "")[0] if value.fget else ("", "Any", "")
            getter = f"    @property\n    def {attr}(self) -> {ret}:"
            pbody = docstring(pdoc, "        ")
            body.append(checked(getter + ("\n" + pbody if pbody else " ...\n"),
                                f"    @property\n    def {attr}(self) -> Any: ...\n"))
            if value.fset:
                body.append(checked(f"    @{attr}.setter\n    def {attr}(self, value: {ret}) -> None: ...\n",
                                    f"    @{attr}.setter\n    def {attr}(self, value: Any) -> None: ...\n"))
        elif isinstance(value, staticmethod):
            text = function(value.__func__, attr, "    ")
            body.append(re.sub(r"^(    (@overload\n    )?)def", r"    @staticmethod\n\1def", text, flags=re.M))
        elif type(value).__name__ == "instancemethod" or (is_routine(value) and attr == "__init__"
                                                          and type(value).__name__ != "wrapper_descriptor"):
            body.append(function(value, attr, "    ", method=True))
        elif not callable(value) and not attr.startswith("__") and not isinstance(value, (property, staticmethod)):
            body.append(f"    {attr}: {type(value).__name__ if type(value).__module__ == 'builtins' else 'Any'}\n")
    out.extend(body or ["    ...\n"])
    return "".join(out)


def stubs(module):
    out = [HEADER, docstring(inspect.cleandoc(module.__doc__ or ""), ""), IMPORTS, "\n"]
    names = sorted(n for n in vars(module) if not (n.startswith("__") and n.endswith("__")) or n == "__version__")
    attributes = [n for n in names if not callable(getattr(module, n)) and not inspect.ismodule(getattr(module, n))]
    for n in attributes:
        value = getattr(module, n)
        out.append(f"{n}: {type(value).__name__ if type(value).__module__ == 'builtins' else 'Any'}\n")
    for n in names:
        value = getattr(module, n)
        if inspect.isclass(value):
            out.append("\n\n" + klass(value, n))
    out.append("\n")
    for n in names:
        value = getattr(module, n)
        if not inspect.isclass(value) and is_routine(value):
            out.append("\n" + function(value, n))
    text = "".join(out)
    ast.parse(text)  # the whole file, once more
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare with the committed stubs; exit 1 if stale")
    parser.add_argument("--out", help="write DIR/hapticfield/__init__.pyi (and py.typed) instead")
    a = parser.parse_args()
    try:
        module = importlib.import_module(MODULE)
    except ImportError as e:
        print(f"make_stubs: cannot import {MODULE} ({e}); set PYTHONPATH to the build's python directory, "
              "e.g. PYTHONPATH=build/python", file=sys.stderr)
        return 2
    text = stubs(module)
    if a.check:
        old = STUB.read_text() if STUB.exists() else ""
        if old == text:
            print(f"make_stubs: {STUB} is current")
            return 0
        sys.stdout.writelines(difflib.unified_diff(old.splitlines(True), text.splitlines(True), str(STUB), "built module"))
        print(f"make_stubs: {STUB} is stale: regenerate with PYTHONPATH=build/python python3 scripts/make_stubs.py",
              file=sys.stderr)
        return 1
    target = pathlib.Path(a.out) / MODULE / "__init__.pyi" if a.out else STUB
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(text)
    (target.parent / "py.typed").write_text("")
    print(f"make_stubs: wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
