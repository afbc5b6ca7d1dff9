"""``mien study``: perception studies. ``stimuli`` renders a design's videos and manifest, ``serve`` runs the web
experiment, ``export`` writes the answers as CSV, ``analyze`` writes the HTML report (see docs/STUDIES.md).

The stimuli folder is ``stimuli -o DIR`` where it is made, ``--stimuli DIR`` where it is read (default:
``stimuli/`` next to the design)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from mien.commands._checks import input_file, output_file, output_folder, output_target, positive_seconds
from mien.commands._vocabulary import add_deprecated_alias, add_emotion_model, add_landmarker, add_output, add_quiet

if TYPE_CHECKING:
    from mien.study.design import Design
    from mien.study.storage import Store


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "study",
        help="perception studies: render stimuli, run the web experiment, export and analyse the answers",
        description="Perception studies as in Broekens et al. and Mascaró et al.: a design TOML file -> "
        "stimuli (rendered or supplied videos) -> a web experiment in the browser -> answers in SQLite or "
        "PostgreSQL -> CSV and an HTML report.",
    )
    parser.set_defaults(handler=lambda _args: parser.print_help() or 0)
    commands = parser.add_subparsers(dest="study_command", metavar="STUDY_COMMAND")

    def with_design(name: str, help_text: str, reads_stimuli: bool = True) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=help_text, description=help_text)
        sub.add_argument("design", type=input_file, help="the study design TOML file")
        if reads_stimuli:
            sub.add_argument(
                "--stimuli",
                type=Path,
                metavar="DIR",
                help="stimuli folder with manifest.json (default: stimuli/ next to the design)",
            )
        return sub

    def with_db(sub: argparse.ArgumentParser) -> None:
        sub.add_argument(
            "--db",
            help="database: a SQLite file or URL, or postgresql://USER@HOST:PORT/DB "
            "(default: STUDY_NAME.sqlite next to the design)",
        )
        sub.add_argument(
            "--busy-timeout",
            type=positive_seconds,
            default=None,
            metavar="SECONDS",
            help="longest wait for a locked or unreachable database per request, retries included; then the "
            "request is refused (HTTP 503 with Retry-After while serving) (default 3)",
        )

    stimuli = with_design(
        "stimuli", "render the design's stimulus videos (or check supplied ones) and write the manifest", False
    )
    add_output(
        stimuli,
        type=output_folder,
        metavar="DIR",
        old=("--stimuli",),
        help="stimuli folder to write, made if missing (default: stimuli/ next to the design)",
    )
    add_quiet(stimuli)
    stimuli.set_defaults(handler=run_stimuli)

    serve = with_design("serve", "run the web experiment (consent, instructions, stimuli, questions, completion)")
    with_db(serve)
    serve.add_argument("--host", default="127.0.0.1", help="address to listen on (default %(default)s)")
    port = serve.add_argument(
        "--http-port", type=int, default=8000, metavar="PORT", help="HTTP port (default %(default)s; 0 = any free port)"
    )
    add_deprecated_alias(serve, "--port", port)
    serve.set_defaults(handler=run_serve)

    export = with_design("export", "write the stored answers as one long CSV (one row per answered question)")
    with_db(export)
    add_output(export, type=output_file, default=Path("answers.csv"), metavar="FILE", old=("--out",),
               help="CSV path (default %(default)s)")  # fmt: skip
    export.set_defaults(handler=run_export)

    analyze = with_design("analyze", "analyse the answers (quality, profiles, rm-ANOVA, plots) into an HTML report")
    with_db(analyze)
    analyze.add_argument("--answers", type=input_file, help="analyse this exported CSV instead of the database")
    add_output(
        analyze,
        type=output_target,
        default=Path("study-report"),
        old=("--out",),
        help="report folder, or a .html file (default %(default)s)",
    )
    add_landmarker(analyze, type=input_file)
    add_emotion_model(analyze, type=input_file)
    add_quiet(analyze)
    analyze.set_defaults(handler=run_analyze)


def _design(args: argparse.Namespace) -> Design:
    from mien.study.design import load_design

    return load_design(args.design)


def _stimuli_folder(args: argparse.Namespace, design: Design) -> Path:
    """The stimuli folder: ``-o`` of ``study stimuli``, ``--stimuli`` of the others, else next to the design."""
    given = args.output if args.study_command == "stimuli" else args.stimuli
    return Path(given) if given is not None else design.path.parent / "stimuli"


def _store(args: argparse.Namespace, design: Design) -> Store:
    from mien.errors import InvalidValueError
    from mien.study.design import check_study_name
    from mien.study.storage import BUSY_TIMEOUT_S, Store, database_url

    check_study_name(design.name, f"{design.path}: study.name")  # it names the default database file
    default = design.path.parent / f"{design.name}.sqlite"
    if default.resolve().parent != design.path.parent.resolve():
        raise InvalidValueError(f"{design.path}: study.name", design.name, "a name without path characters")
    if args.busy_timeout is not None and not args.busy_timeout <= 3600:
        raise InvalidValueError("--busy-timeout", args.busy_timeout, "seconds in (0, 3600]")
    return Store(database_url(args.db, default), busy_timeout_s=args.busy_timeout or BUSY_TIMEOUT_S)


def run_stimuli(args: argparse.Namespace) -> int:
    from mien.study.stimuli import make_stimuli

    design = _design(args)
    folder = _stimuli_folder(args, design)
    result = make_stimuli(design, folder, progress=not args.quiet)
    print(
        f"{len(design.stimuli)} stimuli in {folder} ({result.rendered} made, {result.skipped} already done); "
        f"manifest: {result.manifest_path}"
    )
    return 0


def _checked_manifest(design: Design, folder: Path) -> dict:
    from mien.errors import InvalidValueError
    from mien.study.stimuli import check_design_sha256, load_manifest

    manifest = load_manifest(folder)
    ids = [entry["id"] for entry in manifest["stimuli"]]
    if manifest.get("study") != design.name or ids != [spec.id for spec in design.stimuli]:
        raise InvalidValueError(
            f"{folder / 'manifest.json'}",
            manifest.get("study"),
            f"the manifest of study {design.name!r} with its {len(design.stimuli)} stimuli: re-run "
            f"`mien study stimuli {design.path}`",
        )
    check_design_sha256(manifest, design, folder)
    return manifest


def _stale_manifest(design: Design, folder: Path) -> str | None:
    """Why the stimuli in ``folder`` are not judged by the machine (their manifest is of another version of
    the design), or None (judged, or the report says why not)."""
    from mien.errors import MienError
    from mien.study.stimuli import MANIFEST_NAME, check_design_sha256, load_manifest

    if not (folder / MANIFEST_NAME).is_file():
        return None
    try:
        check_design_sha256(load_manifest(folder, verify=False), design, folder)
    except MienError as error:
        return str(error)
    return None


def run_serve(args: argparse.Namespace) -> int:
    from mien.study.runner import create_app, listen, serve

    sock = listen(args.host, args.http_port)  # first: a taken port is said before any work
    with sock:
        design = _design(args)
        folder = _stimuli_folder(args, design)
        manifest = _checked_manifest(design, folder)
        with _store(args, design) as store:
            store.register_stimuli(design.name, design.protocol, manifest["stimuli"])
            app = create_app(design, manifest, folder, store)
            port = sock.getsockname()[1]
            print(f"study {design.name!r}: http://{args.host}:{port}/?participant=ID  (Ctrl-C to stop)", flush=True)
            serve(app, sock)
    return 0


def run_export(args: argparse.Namespace) -> int:
    from mien.study.export import write_answers_csv

    design = _design(args)
    with _store(args, design) as store:
        path, rows = write_answers_csv(store, args.output, design.name)
    print(f"wrote {rows} answers of study {design.name!r} to {path}")
    return 0


def run_analyze(args: argparse.Namespace) -> int:
    from mien.study.analysis import analyze, analyze_csv
    from mien.study.report import write_report

    design = _design(args)
    factors = list(design.within) or None
    if args.answers is not None:
        result = analyze_csv(args.answers, factors)
    else:
        with _store(args, design) as store:
            frame = store.answers_frame(design.name)
        if frame.empty:
            from mien.errors import InvalidValueError

            raise InvalidValueError(
                "answers", 0, f"at least one stored answer of study {design.name!r} (run `mien study serve` first)"
            )
        # hashed as read: the same SHA-256 as `mien study export` of these answers would have
        result = analyze(frame, factors, source=str(args.db or design.name))
    stimuli = _stimuli_folder(args, design)
    path = write_report(
        result,
        args.output,
        machine=_stale_manifest(design, stimuli),
        stimuli=stimuli,
        landmarker=args.landmarker,
        emotion_model=args.emotion_model,
        progress=not args.quiet,
    )
    print(f"report: {path}")
    return 0
