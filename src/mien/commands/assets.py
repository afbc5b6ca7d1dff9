"""``mien assets``: report which assets (heads, models) are configured and found, and how to install the rest.

Always exits 0: it is a report, not a check.
"""

from __future__ import annotations

import argparse
from typing import Any


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


def _report() -> dict[str, Any]:
    """The report as plain data: config file path and one entry per asset."""
    import os

    from mien.errors import MienError
    from mien.paths import ASSETS, asset_path, config_path

    entries = []
    for name, (env_var, how) in ASSETS.items():
        path = asset_path(name)
        source = "environment" if os.environ.get(env_var) else ("config" if path is not None else None)
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
