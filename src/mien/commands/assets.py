"""``mien assets``: report which assets (heads, models) are configured and found, and how to install the rest;
``mien assets fetch NAME``: download the files mien reads of one from its public home, check each file's hash
and install it.

The report always exits 0: it is a report, not a check. ``fetch`` exits 2, installing nothing, when a download
fails or a file's SHA-256 does not match (after a cut connection it keeps the verified files to resume).
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
    from mien.assets.fetch import SOURCES  # standard library and mien's base only: light

    ict = SOURCES["ict-facekit"]
    fetch = sub.add_parser(
        "fetch",
        help="download an asset from its public home, check every file's SHA-256 and install it where mien looks",
        description=f"Download the files mien reads of NAME (ict-facekit: the {ict.licence} ICT-FaceKit head, "
        f"{ict.download_bytes / 1e6:.0f} MB, from {ict.repository} at commit {ict.commit[:7]}, one by one), check each "
        "against the SHA-256 list of that commit shipped with mien, and install them (default: the user data "
        "folder, $MIEN_DATA_DIR or ~/.local/share/mien, where mien looks when no variable or config entry "
        "points elsewhere). Files stream into a hidden staging folder beside the destination, renamed into "
        "place once all are verified: a cut download is resumed by running the same command again, a file "
        "whose bytes differ installs nothing.",
    )
    fetch.add_argument("name", help="asset to fetch: ict-facekit")
    fetch.add_argument(
        "--url", metavar="BASE", help="fetch FILE from BASE/FILE instead (a mirror serving the pinned commit's files)"
    )
    add_output(
        fetch,
        type=_install_folder,
        metavar="DIR",
        old=("--dest",),
        help="install into this folder (it must not exist yet)",
    )
    fetch.add_argument("--force", action="store_true", help="replace an existing install at the destination")
    fetch.add_argument("--timeout", type=positive_seconds, default=30.0, help="network timeout, seconds (default 30)")
    add_quiet(fetch)
    fetch.set_defaults(handler=run_fetch)


def _install_folder(text: str) -> Path:
    """argparse type: the folder a fetch creates (not yet: the fetch makes it); refused under a regular file."""
    path = Path(text).expanduser()
    existing = path.parent
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: {existing} is a file, so no folder can be made under it")
    return path


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
    try:
        path = fetch_asset(
            name, args.url, args.output, force=args.force, show_progress=not args.quiet, timeout_s=args.timeout
        )
    except KeyboardInterrupt:  # Ctrl-C: the verified files stay for a resume; say so
        import sys

        from mien.assets.fetch import staging_folder
        from mien.paths import installed_path

        staging = staging_folder(args.output or installed_path(SOURCES[name].asset))
        if staging.is_dir():
            print(
                f"the files verified so far are kept in {staging}: run the same command again to resume",
                file=sys.stderr,
            )
        raise
    source = SOURCES[name]
    print(f"installed {name} ({source.licence} licence, {source.repository} at {source.commit[:7]}) in {path}")
    if args.output is not None:
        from mien.paths import ASSETS

        env_var = ASSETS[source.asset][0]
        print(f"mien looks in the default folder only; point {env_var} at {path} to use this one")
    return 0
