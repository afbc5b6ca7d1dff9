"""Copy the part of the npm ``three`` package that mien's viewer loads into a folder (the wheel's
``mien/viewer/three``), with three.js's licence. Run by ``setup.py`` when a wheel or sdist is built; standard
library only, so it runs inside pip's isolated build environment.

What is copied is found, not listed: the viewer's own modules (``src/mien/viewer/static/*.js``) are followed
through their ``import`` statements, with ``three`` and ``three/addons/`` resolved by the page's import map
(``index.html``), to every module they need; a ``"/vendor/three/<folder>/"`` string in them (the Draco
decoder's path) adds that folder's files. To these come ``LICENSE`` and ``package.json`` (the version) of three,
and the licence notes of the decoders three bundles (Draco: Apache-2.0, in ``libs/draco/README.md``; meshopt:
MIT, in its file's header). No other npm package is copied, and the repository never holds three.js: it comes
from ``node_modules`` (``npm ci``), or ``$MIEN_NODE_MODULES``.

    python scripts/vendor_three.py --list          # the files, relative to node_modules/three
    python scripts/vendor_three.py OUT_FOLDER      # copy them into OUT_FOLDER (same layout)
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
STATIC = REPO / "src" / "mien" / "viewer" / "static"
"""The viewer's page, scripts and styles."""
SERVED_AT = "/vendor/three/"
"""Where the server mounts the three folder (mien.viewer.routes)."""
ALWAYS = ("LICENSE", "package.json", "examples/jsm/libs/draco/README.md")
"""Copied beside the modules: three's licence and version, the licence note of the Draco decoder."""

_IMPORT = re.compile(
    r"""^[ \t]*(?:import|export)\b[^'";]*?\bfrom[ \t]*['"]([^'"]+)['"]"""  # import {a} from "x"; export * from "x"
    r"""|^[ \t]*import[ \t]*['"]([^'"]+)['"]"""  # import "x"
    r"""|\bimport\(\s*['"]([^'"]+)['"]\s*\)""",  # import("x")
    re.MULTILINE,
)
_SERVED_PATH = re.compile(r"""['"]/vendor/three/([^'"]*)['"]""")


class VendorError(RuntimeError):
    """three is missing, or the viewer needs something that is not in it."""


def node_modules() -> Path:
    """``$MIEN_NODE_MODULES`` or the checkout's ``node_modules`` (what mien.viewer.vendor looks in too)."""
    configured = os.environ.get("MIEN_NODE_MODULES")
    return Path(configured).expanduser() if configured else REPO / "node_modules"


def _import_map(static: Path) -> dict[str, str]:
    """The page's import map, with ``/vendor/three/`` taken off the targets: specifier -> path in three."""
    page = (static / "index.html").read_text(encoding="utf-8")
    found = re.search(r'<script type="importmap">(.*?)</script>', page, re.DOTALL)
    if found is None:
        raise VendorError(f"{static / 'index.html'}: no import map")
    imports: dict[str, str] = json.loads(found.group(1))["imports"]
    return {name: target.removeprefix(SERVED_AT) for name, target in imports.items() if target.startswith(SERVED_AT)}


def _specifiers(code: str) -> list[str]:
    return [next(g for g in match.groups() if g) for match in _IMPORT.finditer(code)]


def _resolve(specifier: str, importer: str | None, import_map: dict[str, str]) -> str | None:
    """The path in three of ``specifier`` imported from ``importer`` (a path in three; None: a viewer file),
    or None when it is not a three module (one of the viewer's own files)."""
    if specifier in import_map:
        return import_map[specifier]
    for prefix, target in import_map.items():
        if prefix.endswith("/") and specifier.startswith(prefix):
            return target + specifier[len(prefix) :]
    if specifier.startswith((".", "/")):
        if importer is None:
            return None  # the viewer's own "./frame.js"
        return os.path.normpath(os.path.join(os.path.dirname(importer), specifier)).replace(os.sep, "/")
    where = importer or "the viewer"
    raise VendorError(f"{where} imports {specifier!r}, which the import map does not give to three")


def three_files(three: Path, static: Path = STATIC) -> list[str]:
    """Paths, relative to the ``three`` package folder, of every file the viewer loads from it (sorted)."""
    if not (three / "package.json").is_file():
        raise VendorError(f"{three}: no npm three package here; run `npm ci` in the mien checkout")
    import_map = _import_map(static)
    needed: set[str] = set(ALWAYS)
    todo: list[str] = []
    for script in sorted(static.glob("*.js")):
        code = script.read_text(encoding="utf-8")
        todo += [p for s in _specifiers(code) if (p := _resolve(s, None, import_map)) is not None]
        for served in _SERVED_PATH.findall(code):
            folder = three / served
            if served.endswith("/") and folder.is_dir():
                needed.update(p.relative_to(three).as_posix() for p in folder.iterdir() if p.is_file())
            else:
                todo.append(served)
    while todo:
        path = todo.pop()
        if path in needed:
            continue
        if not (three / path).is_file():
            raise VendorError(f"{three / path}: needed by the viewer but missing; run `npm ci`")
        needed.add(path)
        if path.endswith(".js"):
            code = (three / path).read_text(encoding="utf-8")
            todo += [p for s in _specifiers(code) if (p := _resolve(s, path, import_map)) is not None]
    missing = [path for path in ALWAYS if not (three / path).is_file()]
    if missing:
        raise VendorError(f"{three}: {', '.join(missing)} missing; run `npm ci`")
    return sorted(needed)


def copy_three(into: Path, three: Path | None = None, static: Path = STATIC) -> list[str]:
    """Copy :func:`three_files` from ``three`` (default ``node_modules/three``) into ``into`` (replaced)."""
    three = three if three is not None else node_modules() / "three"
    files = three_files(three, static)
    if into.exists():
        shutil.rmtree(into)
    for path in files:
        (into / path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(three / path, into / path)
    return files


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", nargs="?", type=Path, help="folder to copy into (replaced)")
    parser.add_argument("--list", action="store_true", help="print the files instead of copying them")
    args = parser.parse_args(argv)
    try:
        if args.list or args.out is None:
            print("\n".join(three_files(node_modules() / "three")))
        else:
            files = copy_three(args.out)
            print(f"copied {len(files)} files of three.js into {args.out}")
    except VendorError as exc:
        print(f"vendor_three: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
