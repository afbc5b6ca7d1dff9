"""``mien assets``: report which assets (heads, models) are configured and found, and how to install the rest;
``mien assets fetch NAME``: download one from its public home, check its hash and install it.

The report always exits 0: it is a report, not a check. ``fetch`` exits 2, installing nothing, when the
download fails or its SHA-256 does not match.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from mien.commands._checks import positive_seconds
from mien.commands._vocabulary import add_output, add_quiet


def register(subparsers: Any) -> None:
    """Add the ``assets`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "assets",
        help="list assets (ICT-FaceKit head, MediaPipe model, emotion model): found or how to install",
        description="Report each asset mien can use: where it is configured (environment variable or the "
        "[assets] table of the config file), whether it is found, and how to install what is missing.",
    )
    parser.add_argument("--json", action="store_true", help="print a machine-readable JSON report")
    parser.set_defaults(handler=run)
    sub = parser.add_subparsers(dest="assets_command", metavar="ACTION")
    fetch = sub.add_parser(
        "fetch",
        help="download an asset from its public home, check its SHA-256 and install it where mien looks",
        description="Download NAME (ict-facekit: the MIT ICT-FaceKit head, GitHub's zip of "
        "https://github.com/ICT-VGL/ICT-FaceKit), check the archive's SHA-256, unpack it into a temporary "
        "folder and rename it into place (default: the user data folder, $MIEN_DATA_DIR or "
        "~/.local/share/mien, where mien looks when no variable or config entry points elsewhere). A failed "
        "or mismatching download installs nothing.",
    )
    fetch.add_argument("name", help="asset to fetch: ict-facekit")
    fetch.add_argument("--url", help="download from this URL instead (a mirror, or a zip of a pinned commit)")
    fetch.add_argument("--sha256", metavar="HEX", help="the SHA-256 the archive must have (64 hex digits)")
    add_output(
        fetch, type=Path, metavar="DIR", old=("--dest",), help="install into this folder (it must not exist yet)"
    )
    fetch.add_argument("--force", action="store_true", help="replace an existing install at the destination")
    fetch.add_argument("--timeout", type=positive_seconds, default=30.0, help="network timeout, seconds (default 30)")
    add_quiet(fetch)
    fetch.set_defaults(handler=run_fetch)


def _report() -> dict[str, Any]:
    """The report as plain data: config file path and one entry per asset."""
    import os

    from mien.errors import MienError
    from mien.paths import ASSETS, INSTALL_FOLDERS, asset_path, config_path, installed_path

    entries = []
    for name, (env_var, how) in ASSETS.items():
        path = asset_path(name)
        source = None
        if os.environ.get(env_var):
            source = "environment"
        elif path is not None:
            source = "installed" if name in INSTALL_FOLDERS and path == installed_path(name) else "config"
        entry: dict[str, Any] = {
            "name": name,
            "env_var": env_var,
            "configured": path is not None,
            "source": source,
            "path": None if path is None else str(path),
            "found": bool(path is not None and path.exists()),
            "how_to_install": how,
        }
        if name == "ict_facekit" and entry["found"]:
            from mien.rig.ict_facekit import ict_cache_file, ict_missing_files

            try:
                missing = ict_missing_files(path)
                entry["complete"] = not missing
                entry["missing_files"] = missing
                entry["cache_built"] = bool(not missing and ict_cache_file(path).is_file())
            except MienError as exc:  # unreadable folder: report, do not fail
                entry["complete"] = False
                entry["error"] = str(exc)
        entries.append(entry)
    return {"config_file": str(config_path()), "assets": entries}


def _text(report: dict[str, Any]) -> str:
    lines = []
    for entry in report["assets"]:
        name, env_var = entry["name"], entry["env_var"]
        if entry["found"] and entry.get("complete", True):
            status = "found"
        elif entry["found"]:
            status = "INCOMPLETE"
        elif entry["configured"]:
            status = "NOT FOUND"
        else:
            status = "not configured"
        lines.append(f"{name}: {status}")
        if entry["path"]:
            lines.append(f"  path: {entry['path']} (from {entry['source']})")
        if entry.get("missing_files"):
            missing = entry["missing_files"]
            more = " ..." if len(missing) > 8 else ""
            lines.append(f"  missing {len(missing)} files: {', '.join(missing[:8])}{more}")
        if "error" in entry:
            lines.append(f"  error: {entry['error']}")
        if "cache_built" in entry and entry.get("complete"):
            built = "built" if entry["cache_built"] else "not built yet (the first load parses the OBJ files)"
            lines.append(f"  cache: {built}")
        if not (entry["found"] and entry.get("complete", True)):
            lines.append(f"  install: {entry['how_to_install']}")
            lines.append(f"  then: export {env_var}=/path/to/it")
            lines.append(f"    or in {report['config_file']}:")
            lines.append(f'      [assets]\n      {name} = "/path/to/it"')
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Print the asset report (text, or JSON with ``--json``); always returns 0."""
    import json

    report = _report()
    print(json.dumps(report, indent=2) if args.json else _text(report))
    return 0


def run_fetch(args: argparse.Namespace) -> int:
    """Download, verify and install ``args.name``; print the install path. Exit 2 (nothing installed) on failure."""
    from mien.assets.fetch import SOURCES, fetch_asset
    from mien.errors import UnknownNameError

    name = args.name.replace("_", "-").lower()
    if name not in SOURCES:
        raise UnknownNameError("fetchable asset", args.name, tuple(SOURCES))
    verify = None
    if SOURCES[name].asset == "ict_facekit":
        from mien.rig.ict_facekit import ict_missing_files

        verify = ict_missing_files
    path = fetch_asset(
        name,
        args.url,
        args.sha256,
        args.output,
        force=args.force,
        show_progress=not args.quiet,
        timeout_s=args.timeout,
        verify=verify,
    )
    print(f"installed {name} ({SOURCES[name].licence} licence) in {path}")
    if args.output is not None:
        from mien.paths import ASSETS

        env_var = ASSETS[SOURCES[name].asset][0]
        print(f"mien looks in the default folder only; point {env_var} at {path} to use this one")
    return 0
