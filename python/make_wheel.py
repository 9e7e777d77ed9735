#!/usr/bin/env python3
"""Writes the hapticfield wheel from a built module, with the standard library only.

    make_wheel.py --module __init__.cpython-311-x86_64-linux-gnu.so --stubs python/stubs/hapticfield
                  --modules python/hapticfield/batch.py --readme python/README.md --version 0.1.0 --out DIR

The wheel (PEP 427, binary distribution format) holds the package hapticfield/: the extension as
its __init__, the type stubs __init__.pyi and the PEP 561 marker py.typed, the pure-Python modules
(hapticfield.batch), and hapticfield-V.dist-info/
with METADATA, WHEEL and RECORD (sha256 of every file). Its tag is the running interpreter's (e.g.
cp311-cp311-linux_x86_64): run it with the Python the module was built for. Prints the wheel's path.
"""
import argparse
import base64
import hashlib
import os
import pathlib
import sys
import sysconfig
import time
import zipfile

NAME = "hapticfield"
SUMMARY = "Haptic fields (tangible images, textures, friction, contact) evaluated in C++, and a servo loop"


def fail(message):
    print(f"make_wheel: {message}", file=sys.stderr)
    sys.exit(1)


def tag():
    """The interpreter, ABI and platform tags of this Python (PEP 425)."""
    if sys.implementation.name != "cpython":
        fail(f"a CPython extension cannot be tagged for {sys.implementation.name}")
    version = f"{sys.version_info.major}{sys.version_info.minor}"
    abi = "cp" + version + ("t" if sysconfig.get_config_var("Py_GIL_DISABLED") else "")
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return f"cp{version}-{abi}-{platform}"


def record_hash(data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode("ascii")
    return f"sha256={digest}"


def metadata(version, readme):
    lines = [
        "Metadata-Version: 2.1",
        f"Name: {NAME}",
        f"Version: {version}",
        f"Summary: {SUMMARY}",
        "Requires-Python: >=3.9",
        "Requires-Dist: numpy",
        "Description-Content-Type: text/markdown",
    ]
    return "\n".join(lines) + "\n\n" + readme


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--module", required=True, type=pathlib.Path, help="the built extension")
    parser.add_argument("--stubs", required=True, type=pathlib.Path, help="the directory of __init__.pyi and py.typed")
    parser.add_argument("--modules", nargs="*", default=[], type=pathlib.Path,
                        help="pure-Python modules of the package (e.g. python/hapticfield/batch.py)")
    parser.add_argument("--readme", required=True, type=pathlib.Path, help="the long description (Markdown)")
    parser.add_argument("--version", required=True)
    parser.add_argument("--out", required=True, type=pathlib.Path, help="the directory the wheel is written to")
    args = parser.parse_args()

    suffix = sysconfig.get_config_var("EXT_SUFFIX")
    if not args.module.name.endswith(suffix):
        fail(f"{args.module.name} was not built for this Python ({sys.executable}, extensions end in {suffix})")
    wheel_tag = tag()
    dist_info = f"{NAME}-{args.version}.dist-info"
    files = [  # (path in the wheel, bytes, executable)
        (f"{NAME}/__init__{suffix}", args.module.read_bytes(), True),
        (f"{NAME}/__init__.pyi", (args.stubs / "__init__.pyi").read_bytes(), False),
        (f"{NAME}/py.typed", (args.stubs / "py.typed").read_bytes(), False),
        *((f"{NAME}/{m.name}", m.read_bytes(), False) for m in sorted(args.modules)),
        (f"{dist_info}/METADATA", metadata(args.version, args.readme.read_text(encoding="utf-8")).encode(), False),
        (f"{dist_info}/WHEEL",
         f"Wheel-Version: 1.0\nGenerator: {NAME} make_wheel.py\nRoot-Is-Purelib: false\nTag: {wheel_tag}\n".encode(),
         False),
        (f"{dist_info}/top_level.txt", f"{NAME}\n".encode(), False),
    ]
    record = "".join(f"{path},{record_hash(data)},{len(data)}\n" for path, data, _ in files)
    record += f"{dist_info}/RECORD,,\n"
    files.append((f"{dist_info}/RECORD", record.encode(), False))

    args.out.mkdir(parents=True, exist_ok=True)
    wheel = args.out / f"{NAME}-{args.version}-{wheel_tag}.whl"
    # Fixed dates (SOURCE_DATE_EPOCH when given; zip cannot go before 1980): the same inputs, the same bytes.
    epoch = max(int(os.environ.get("SOURCE_DATE_EPOCH", "315532800")), 315532800)
    date_time = time.gmtime(epoch)[:6]
    partial = wheel.with_name(wheel.name + ".part")
    with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for path, data, executable in files:  # RECORD last, as PEP 427 recommends
            info = zipfile.ZipInfo(path, date_time=date_time)
            info.external_attr = (0o100755 if executable else 0o100644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
    partial.replace(wheel)
    print(wheel)


if __name__ == "__main__":
    main()
