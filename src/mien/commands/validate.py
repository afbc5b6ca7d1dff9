"""``mien validate``: measure how the faces read to detectors (rig fidelity, emotion recognition, OpenFACS
comparison with a human video) and write a citable HTML report."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from mien.commands._checks import input_file, input_folder, output_folder
from mien.commands._vocabulary import add_emotion_model, add_landmarker, add_output, add_quiet, basis_list, head_list
from mien.render.camera import VIEWS

__all__ = ["parse_heads", "register"]

_VIEWS_STUDY = tuple(VIEWS)


def parse_heads(specs: list[str] | None) -> list[tuple[str, str]]:
    """``["ict:a", "builtin"]`` -> ``[("ict", "a"), ("builtin", "default")]``; None -> every installed head.

    Installed heads: the built-in head (identities default and b) and, when ICT-FaceKit is installed, its
    identities a and b (the study's two morphologies).
    """
    from mien.rig.heads import ict_installed, parse_head_spec, resolve_head_name

    if not specs:
        heads = [("builtin", "default"), ("builtin", "b")]
        return [("ict", "a"), ("ict", "b"), *heads] if ict_installed() else heads
    out = []
    for spec in specs:
        for item in spec.split(","):
            head, identity = parse_head_spec(item.strip())
            head = resolve_head_name(head)
            out.append((head, identity or ("a" if head == "ict" else "default")))
    return out


def _check_heads(heads: list[tuple[str, str]]) -> None:
    """Fail early, naming the head, when a head or identity is unknown or not installed."""
    from mien.errors import MissingAssetError, UnknownNameError
    from mien.rig.builtin_head import BUILTIN_IDENTITIES
    from mien.rig.heads import ict_installed

    for head, identity in heads:
        if head == "file":
            from mien.rig.files.head import is_head_file

            if not is_head_file(identity):
                raise MissingAssetError(f"head file {identity} not found: give a .glb, .gltf, .vrm or OBJ folder")
        elif head == "ict":
            if not ict_installed():
                raise MissingAssetError(
                    "head 'ict' is not installed: point MIEN_ICT_FACEKIT (or [assets] ict_facekit in the config "
                    "file) at the ICT-FaceKit folder that holds FaceXModel/ (see `mien assets`)"
                )
            from mien.rig.ict_facekit import ict_identity_presets

            if identity not in ict_identity_presets():
                raise UnknownNameError("ICT identity", identity, tuple(ict_identity_presets()))
        elif identity not in BUILTIN_IDENTITIES:
            raise UnknownNameError("built-in identity", identity, tuple(BUILTIN_IDENTITIES))


def _add_common(parser: argparse.ArgumentParser, default_out: str) -> None:
    add_output(
        parser,
        type=output_folder,
        default=Path(default_out),
        metavar="DIR",
        dest="out",
        old=("--out",),
        help="output folder, made if missing (default %(default)s)",
    )
    parser.add_argument(
        "--head",
        action="append",
        type=head_list,
        metavar="HEAD[:IDENTITY]",
        help="head to validate, repeatable or comma-separated: ict:a, ict:b, builtin:default, builtin:b, a "
        "character file (face.glb) "
        "(default: every installed head and identity)",
    )
    add_landmarker(parser, type=input_file)
    add_emotion_model(parser, type=input_file)
    parser.add_argument(
        "--framing",
        choices=("averaged", "landmarks", "fer"),
        default="averaged",
        help="how a verdict is judged: averaged (the default: the classifier's probabilities averaged over both "
        "framings, jittered, at two render sizes; see docs/VALIDATION.md), or one framing's crops only to compare: "
        "landmarks (brows to chin) or fer (the fer package's Haar-box framing, forehead to chin)",
    )
    parser.add_argument("--size", default="512x512", help="render size WIDTHxHEIGHT (default %(default)s)")
    add_quiet(parser)


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``validate`` and its subcommands."""
    parser = subparsers.add_parser(
        "validate",
        help="measure how the faces read: rig fidelity, emotion recognition, human-video comparison, HTML report",
        description="Render mien's faces, run detectors over them (MediaPipe Face Landmarker, the FER emotion "
        "classifier) and measure: each AU commanded vs detected (rig), the study's emotions recognised "
        "(emotions), a human video vs the character (compare), and all of it in one HTML page (report).",
    )
    sub = parser.add_subparsers(dest="validate_command", metavar="WHAT")

    rig = sub.add_parser("rig", help="every AU at A..E on each head: commanded vs detected, cross-talk")
    _add_common(rig, "mien-validate/rig")
    rig.add_argument("--aus", help="AU numbers, comma-separated (default: the 18 OpenFACS AUs)")
    rig.add_argument(
        "--human-data",
        type=input_folder,
        help="folder of real human media (video/, images/) to check which AUs the detector sees on people "
        "(default: $MIEN_SHARED/data)",
    )
    rig.set_defaults(handler=run_rig)

    emotions = sub.add_parser("emotions", help="the study's 6 emotions and 4 blends: recognition, confusion, quality")
    _add_common(emotions, "mien-validate/emotions")
    emotions.add_argument(
        "--views",
        default=",".join(_VIEWS_STUDY),
        help="camera views, comma-separated from " + ", ".join(_VIEWS_STUDY) + " (default: all)",
    )
    emotions.add_argument("--intensities", default="1.2,2.4", help="emotion intensities (default %(default)s)")
    emotions.add_argument(
        "--basis",
        type=basis_list,
        default="facs,feature_points",
        help="expression bases, comma-separated: facs, feature_points (default both)",
    )
    emotions.add_argument("--expressions", help="comma-separated subset of the ten expressions (default all)")
    emotions.set_defaults(handler=run_emotions)

    compare = sub.add_parser("compare", help="a human video vs the character (OpenFACS Fig. 5, and the closed loop)")
    compare.add_argument("video", type=input_file, help="video of a person performing the expression")
    _add_common(compare, "mien-validate/compare")
    compare.add_argument("--expression", help="emotion, blend or AUs the person performs (e.g. joy); "
                         "without it only the closed loop runs")  # fmt: skip
    compare.add_argument("--camera", default="frontal-1m", help="camera preset (default %(default)s)")
    compare.add_argument("--length", type=int, default=100, help="time samples per activation map (default 100)")
    compare.set_defaults(handler=run_compare_command)

    report = sub.add_parser("report", help="everything above in one self-contained HTML page")
    _add_common(report, "mien-validate")
    report.add_argument("--video", type=input_file, help="human video for the comparison section (optional)")
    report.add_argument("--human-data", type=input_folder, help="real human media folder for the rig section")
    report.add_argument("--expression", default="joy", help="expression the video shows (default %(default)s)")
    report.set_defaults(handler=run_report)

    def show_help(args: argparse.Namespace) -> int:
        parser.print_help()
        return 0

    parser.set_defaults(handler=show_help)


def _size(args: argparse.Namespace) -> tuple[int, int]:
    from mien.commands._scene import parse_size

    return parse_size(args.size)


def _list(text: str, field: str, parse: Any = str) -> list[Any]:
    from mien.errors import InvalidValueError

    items = [item.strip() for item in text.split(",") if item.strip()]
    try:
        values = [parse(item) for item in items]
    except ValueError:
        raise InvalidValueError(field, text, "a comma-separated list") from None
    if not values:
        raise InvalidValueError(field, text, "at least one value")
    return values


def _options(args: argparse.Namespace, **study: Any) -> Any:
    """The library's :class:`~mien.validate.options.ValidateOptions` from the parsed arguments (``study``: the
    recognition study's conditions, where the command has them)."""
    from mien.validate.options import ValidateOptions

    return ValidateOptions(
        out_dir=Path(args.out),
        size_px=_size(args),
        landmarker_path=args.landmarker,
        emotion_model_path=args.emotion_model,
        framing=args.framing,
        show_progress=not args.quiet,
        human_data_dir=getattr(args, "human_data", None),
        video_path=getattr(args, "video", None),
        video_expression=getattr(args, "expression", None) or "joy",
        **study,
    )


def _detector(args: argparse.Namespace, emotions: bool = True) -> Any:
    from mien.validate.options import open_detector

    return open_detector(_options(args), emotions)


def emotions_result(args: argparse.Namespace, heads: list[tuple[str, str]]) -> Any:
    """Run the recognition study for ``heads`` from the parsed options."""
    from mien.validate.expressions import EXPRESSIONS
    from mien.validate.recognition import recognition_study

    study = {
        "bases": tuple(b.replace("-", "_") for b in _list(args.basis, "basis")),
        "views": tuple(_list(args.views, "views")),
        "intensities": tuple(_list(args.intensities, "intensities", float)),
        "expressions": tuple(_list(args.expressions, "expressions")) if args.expressions else EXPRESSIONS,
    }
    return recognition_study(heads, _options(args, **study))


def _percent(value: float) -> str:
    """``"97%"``, or ``"-"`` for a rate over nothing (nan)."""
    return f"{value:.0%}" if math.isfinite(value) else "-"


def run_emotions(args: argparse.Namespace) -> int:
    """``mien validate emotions``."""
    from mien.validate.expressions import BASICS, EXPRESSIONS
    from mien.validate.recognition import write_recognition
    from mien.validate.targets import FRONTAL, check_targets, scorecard_lines

    heads = parse_heads(args.head)
    _check_heads(heads)
    result = emotions_result(args, heads)
    written = write_recognition(result, args.out)
    print(
        f"recognised (the averaged judge's top label; blends: one of its components) over {len(result.scores)} renders,"
        " the spread across crops, and the FACS reading:"
    )
    without_quality = 0
    for name in ("neutral", *EXPRESSIONS):
        if not result.subset(expression=name):
            continue  # not asked for
        facs = "" if name == "neutral" else f"   FACS reading {_percent(result.facs_rate(expression=name)):>4s}"
        quality = result.quality(name)  # nan for a blend: no target label
        without_quality += not math.isfinite(quality)
        shown = f"{quality:.2f}" if math.isfinite(quality) else " n/a"
        low, high = result.spread(expression=name)
        spread = f" (crops {_percent(low)}-{_percent(high)})" if math.isfinite(low) else ""
        print(f"  {name:13s} {result.rate(expression=name):6.0%}{spread}   quality {shown}{facs}")
    if without_quality:
        print(
            "  quality n/a: none of the classifier's 7 labels is a blend (a blend is recognised when its top label"
            " is one of its two emotions')"
        )
    frontal = result.rate(expression=BASICS, view=FRONTAL)
    print(f"{', '.join(BASICS)}, frontal: {_percent(frontal)}")
    summary = result.framing_summary()
    if len(summary) > 1:
        print("the five (frontal / 45 degrees) and neutral, by the verdict and by each framing's crops alone:")
        for framing, rates in summary.items():
            used = " (used above)" if framing == result.framing else ""
            figures = " / ".join(_percent(rates[k]) for k in ("frontal", "oblique"))
            print(f"  {framing + used:23s} {figures}, neutral {_percent(rates['neutral'])}")
    if result.subset(expression="disgust"):
        by_classifier = result.label_rate("angry", expression="disgust")
        by_facs = result.facs_rate("anger", expression="disgust")
        print(f"disgust taken for anger: classifier {by_classifier:.0%}, FACS reading {by_facs:.0%}")
        for basis, by_name in result.disgust_signs().items():
            signs = ", ".join(f"{name} AU9 {au['AU9']:.1f} AU10 {au['AU10']:.1f}" for name, au in by_name.items())
            print(f"  on the mesh's landmarks (0..5), {basis}: {signs}")
    print("targets per head (mien.validate.targets), over the renders of this run:")
    print("\n".join(scorecard_lines(check_targets(result))))
    print(f"wrote {len(written)} files to {args.out} (recognition.json, sheet_*.png, confusion.png, quality.png)")
    return 0


def run_rig(args: argparse.Namespace) -> int:
    """``mien validate rig``."""
    from mien.facs.catalogue import OPENFACS_AUS
    from mien.validate.rig_fidelity import run_rig_fidelity

    heads = parse_heads(args.head)
    _check_heads(heads)
    aus = _list(args.aus, "aus", int) if args.aus else list(OPENFACS_AUS)
    detector = _detector(args, emotions=False)
    try:
        result = run_rig_fidelity(
            heads, aus, size=_size(args), detector=detector, progress=not args.quiet, human_data=args.human_data
        )
    finally:
        detector.close()
    written = result.write(args.out)
    print(result.summary())
    print(f"wrote {args.out}: {', '.join(sorted(path.name for path in written.values()))}")
    return 0


def run_compare_command(args: argparse.Namespace) -> int:
    """``mien validate compare VIDEO``."""
    from mien.validate.compare import run_compare

    heads = parse_heads(args.head)[:1] if args.head else [("default", "")]
    head, identity = heads[0]
    if head != "default":
        _check_heads(heads)
    result = run_compare(
        args.video,
        args.expression,
        head=head,
        identity=identity or None,
        camera=args.camera,
        size=_size(args),
        length=args.length,
        progress=not args.quiet,
        landmarker=args.landmarker,
    )
    written = result.write(args.out)
    print(f"closed loop (human -> character -> detector): r = {result.closed_loop.r:.2f}")
    if result.expression is not None:
        print(f"{args.expression}: human vs character activation maps r = {result.expression.r:.2f}")
    print(f"wrote {args.out}: {', '.join(sorted(path.name for path in written.values()))}")
    return 0


def run_report(args: argparse.Namespace) -> int:
    """``mien validate report``: rig, emotions and (with --video) compare, then one HTML page."""
    from mien.validate.report import build_report

    heads = parse_heads(args.head)
    _check_heads(heads)
    if args.video is not None and not Path(args.video).is_file():
        from mien.errors import InvalidValueError

        raise InvalidValueError("video", str(args.video), "an existing video file of a person")
    path = build_report(heads, _options(args))
    print(f"wrote {path}")
    return 0
