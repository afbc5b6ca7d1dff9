"""``mien serve``: the live server (OpenFACS UDP, WebSocket frames, HTTP API) until Ctrl-C or SIGTERM.

Both signals stop it the same clean way (sockets closed, exit 130 after Ctrl-C, 0 after SIGTERM), even when it
was started with SIGINT ignored (a background job of a script): its own handlers replace the inherited ones."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file
from mien.commands._vocabulary import add_head, add_landmarker, add_token


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "serve",
        help="serve live faces: OpenFACS UDP API, WebSocket frames, HTTP API",
        description="Run the live server: a drop-in OpenFACS UDP endpoint (port 5000), a WebSocket stream of "
        "binary frames (/ws) and an HTTP API with an OpenAPI description (/openapi.json). "
        "Beyond loopback, HTTP and WebSocket need an access token (printed at start).",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address of every endpoint (default %(default)s)")
    parser.add_argument(
        "--udp-port", type=int, default=5000, metavar="PORT", help="OpenFACS UDP port (default %(default)s)"
    )
    parser.add_argument(
        "--http-port", type=int, default=8000, metavar="PORT", help="HTTP + WebSocket port (default %(default)s)"
    )
    parser.add_argument("--tick-hz", type=float, default=60.0, help="clock rate in Hz (default %(default)s)")
    parser.add_argument(
        "--max-viewers",
        type=int,
        default=None,
        metavar="N",
        help="WebSocket viewers served at once; more are refused with close code 1013 and counted (default 200)",
    )
    add_token(parser, help="access token (default: none on loopback, generated beyond)")
    parser.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="a web origin (http://localhost:3000) whose pages may use the server besides its own viewer "
        "(repeatable; others get 403, see docs/SERVER.md, Security)",
    )
    parser.add_argument(
        "--character",
        action="append",
        metavar="ID",
        help="character id to create at start (repeatable; default: one called 'default')",
    )
    add_head(
        parser,
        help="head of those characters: default, builtin or ict, with an optional identity (ict:b), or a head file "
        "(face.glb, .gltf, .vrm, file:PATH), which the viewer shows as itself, textures and all",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the first character (others: +1 each)")
    parser.add_argument("--no-idle", action="store_true", help="switch idle behaviour off")
    parser.add_argument(
        "--capture",
        metavar="SOURCE",
        help="a camera (/dev/video0, camera:0) or a video file played at its real rate: the first character's face "
        "follows the person in it (emotions, laughter and idle still add on top; see docs/SERVER.md, Capture)",
    )
    parser.add_argument(
        "--follow",
        action="append",
        default=[],
        metavar="ID",
        help="a character that follows --capture (repeatable: a second one mirrors the first; default: the first)",
    )
    parser.add_argument("--capture-loop", action="store_true", help="play a --capture video file in a loop")
    add_landmarker(parser, type=input_file)
    parser.add_argument("--check", action="store_true", help="start, print the addresses, then stop (a smoke test)")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import asyncio
    import contextlib
    import dataclasses
    import logging
    import math
    import signal
    import sys

    from mien.errors import InvalidValueError, MienError

    if not (math.isfinite(args.tick_hz) and 1.0 <= args.tick_hz <= 1000.0):
        raise InvalidValueError("--tick-hz", args.tick_hz, "a clock rate between 1 and 1000 Hz")
    for option, port in (("--udp-port", args.udp_port), ("--http-port", args.http_port)):
        if not 0 <= port <= 65535:
            raise InvalidValueError(option, port, "a port 0..65535 (0 = any free port)")
    if args.udp_port and args.udp_port == args.http_port:
        raise InvalidValueError("--http-port", args.http_port, "a port other than --udp-port")
    if args.max_viewers is not None and args.max_viewers < 0:
        raise InvalidValueError("--max-viewers", args.max_viewers, "a number of viewers >= 0")
    from mien.extras import require

    require("mien.server.app", "serve")  # a missing fastapi/uvicorn names mien[serve]
    from mien.server.app import LiveServer, ServeConfig, is_loopback
    from mien.server.capture_source import CaptureConfig, CaptureSource
    from mien.server.registry import CharacterSpec

    ids = args.character or ["default"]
    capture = None
    if args.capture is None:
        for option, given in (("--follow", args.follow), ("--capture-loop", args.capture_loop),
                              ("--landmarker", args.landmarker)):  # fmt: skip
            if given:
                raise InvalidValueError(option, given, "--capture SOURCE as well (it applies to a capture source)")
    else:
        for character_id in args.follow:
            if character_id not in ids:
                raise InvalidValueError("--follow", character_id, f"one of the --character ids {ids}")
        model = str(args.landmarker) if args.landmarker is not None else None
        capture = CaptureConfig(args.capture, tuple(args.follow), loop=args.capture_loop, model=model)
        CaptureSource(capture).check()  # a missing or busy camera, an unreadable video: exit 2 before serving
    specs = tuple(
        CharacterSpec(character_id, head=args.head, identity=args.identity, seed=args.seed + i, idle=not args.no_idle)
        for i, character_id in enumerate(ids)
    )
    config = ServeConfig(args.host, args.udp_port, args.http_port, args.tick_hz, args.token, specs)
    config = dataclasses.replace(config, allow_origins=tuple(args.allow_origin), capture=capture)
    if args.max_viewers is not None:
        config = dataclasses.replace(config, max_viewers=args.max_viewers)
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(name)s %(levelname)s: %(message)s")
    server = LiveServer(config)
    received: list[int] = []

    async def main() -> None:
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()

        def on_signal(signum: int) -> None:
            received.append(signum)
            stop.set()

        handled = []
        for signum in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):  # Windows: Ctrl-C as before
                loop.add_signal_handler(signum, on_signal, signum)
                handled.append(signum)
        try:
            await _serve(stop)
        finally:
            for signum in handled:
                loop.remove_signal_handler(signum)

    async def _serve(stop: asyncio.Event) -> None:
        try:
            await server.start()
        except OSError as exc:
            raise MienError(
                f"cannot listen on {args.host} (UDP {args.udp_port}, HTTP {args.http_port}): {exc.strerror or exc}; "
                "pick other ports with --udp-port/--http-port (0 = any free port) or stop the other server"
            ) from None
        host = f"[{args.host}]" if ":" in args.host else args.host
        query = f"?token={server.token}" if server.token else ""
        print(f"mien serve: OpenFACS UDP on {host}:{server.udp_port}", flush=True)
        print(f"mien serve: HTTP on http://{host}:{server.http_port}/{query} (OpenAPI: /openapi.json)", flush=True)
        print(f"mien serve: WebSocket frames on ws://{host}:{server.http_port}/ws{query}", flush=True)
        print(f"mien serve: characters {', '.join(ids)} at {args.tick_hz:g} Hz; Ctrl-C or SIGTERM stops", flush=True)
        if capture is not None:
            followers = ", ".join(capture.characters or ids[:1])
            print(f"mien serve: capture {capture.source} drives {followers} (state: /api/capture)", flush=True)
        if not is_loopback(args.host):
            print(f"mien serve: WARNING: listening beyond loopback; access token: {server.token}", flush=True)
        try:
            if args.check:
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(stop.wait(), 0.5)
            else:
                await stop.wait()
        finally:
            await server.stop()

    asyncio.run(main())
    if signal.SIGINT in received:
        print("interrupted", file=sys.stderr)
        return 130
    if received:
        print("mien serve: stopped (SIGTERM)", file=sys.stderr)
    return 0
