"""``mien send``: one message to a running ``mien serve`` (UDP like OpenFACS, or WebSocket with ``--ws``)."""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "send",
        help="send AUs, an emotion, PAD or a laugh to a running server",
        description="Send one message to `mien serve`: the full AU state (--au, missing AUs are 0, as in "
        "OpenFACS), an emotion event, a PAD state or a laugh. UDP by default (no reply); --ws sends it over "
        "the WebSocket and reports the frame that shows it.",
    )
    parser.add_argument("--au", action="append", metavar="AU=INTENSITY", help="e.g. AU12=3 or AU6L=1.5 (repeatable)")
    parser.add_argument("--speed", type=float, help="OpenFACS Speed 0..1 per tick at 60 Hz (default 0.05 with --au)")
    parser.add_argument("--emotion", help="emotion or blend name (joy, sadness, ..., furious)")
    parser.add_argument("--laugh", help="laugh or smile type (e.g. laughter)")
    parser.add_argument("--intensity", type=float, default=1.0, help="intensity of --emotion / --laugh, 0..5")
    parser.add_argument("--pad", nargs=3, type=float, metavar=("P", "A", "D"), help="PAD state, each -1..1")
    parser.add_argument("--character", metavar="ID", help="target character (default: the server's first)")
    parser.add_argument("--host", default="127.0.0.1", help="server address (default %(default)s)")
    parser.add_argument("--port", type=int, help="UDP port (default 5000), or HTTP port with --ws (default 8000)")
    parser.add_argument("--ws", action="store_true", help="send over the WebSocket instead of UDP")
    parser.add_argument("--token", help="access token (--ws to a server beyond loopback)")
    parser.set_defaults(handler=run)


def _message(args: argparse.Namespace) -> dict[str, object]:
    from mien.errors import InvalidValueError

    message: dict[str, object] = {}
    for item in args.au or ():
        name, sep, value = item.partition("=")
        try:
            message[name.strip()] = float(value) if "." in value or "e" in value.lower() else int(value)
        except ValueError:
            sep = ""
        if not sep:
            raise InvalidValueError("--au", item, "AU=INTENSITY such as AU12=3 or AU6L=1.5")
    if args.au or args.speed is not None:
        message["Speed"] = 0.05 if args.speed is None else args.speed
    if args.emotion is not None:
        message["emotion"] = args.emotion
    if args.laugh is not None:
        message["laugh"] = args.laugh
    if args.emotion is not None or args.laugh is not None:
        message["intensity"] = args.intensity
    if args.pad is not None:
        message["pad"] = list(args.pad)
    if args.character is not None:
        message["character"] = args.character
    if not message:
        raise InvalidValueError("message", "(nothing)", "at least one of --au, --speed, --emotion, --laugh, --pad")
    return message


def run(args: argparse.Namespace) -> int:
    import json

    from mien.errors import InvalidValueError
    from mien.server.protocol import MessageRejected, parse_message

    message = _message(args)
    data = json.dumps(message).encode()
    try:
        parse_message(data)  # the server's own parser: a bad value is refused here, with its reason
    except MessageRejected as exc:
        raise InvalidValueError("message", message, f"a valid message ({exc.detail})") from None
    if args.port is not None and not 0 < args.port <= 65535:
        raise InvalidValueError("--port", args.port, "a port 1..65535")
    if not args.ws:
        from mien.client import UdpClient, openfacs_message

        with UdpClient(args.host, args.port or 5000) as client:
            if args.au or args.speed is not None:
                aus = {k: v for k, v in message.items() if k.startswith("AU")}
                rest = {k: v for k, v in message.items() if not k.startswith("AU") and k != "Speed"}
                client.send_raw(openfacs_message(aus, message["Speed"], **rest))  # type: ignore[arg-type]
            else:
                client.send_raw(data)
        print(f"sent {len(data)} bytes to udp://{args.host}:{args.port or 5000}")
        return 0
    from mien.client import WebSocketClient

    url = f"ws://{args.host}:{args.port or 8000}/ws"
    with WebSocketClient(url, character=args.character, token=args.token) as client:
        client.send(message)
        try:
            frame = client.recv_frame(timeout_s=5.0)
        except TimeoutError:
            raise InvalidValueError("--ws", url, "a server that streams frames (none came in 5 s)") from None
        except Exception as exc:
            raise InvalidValueError("--ws", url, f"a server that keeps the connection open ({exc})") from None
    print(f"sent {len(data)} bytes to {url}; frame tick {frame.tick} at {frame.time_s:.3f} s")
    return 0
