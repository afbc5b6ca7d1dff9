"""``mien send``: one message to a running ``mien serve`` (UDP like OpenFACS, or WebSocket with ``--ws``).

UDP has no reply, so a plain send says only that the datagram left; ``--check`` asks the server over HTTP first
(does the character exist?) and after (did the server accept the message, or refuse it and why?), exit 2 when
not."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from mien.commands._vocabulary import add_deprecated_option, add_token

if TYPE_CHECKING:
    from mien.client import HttpClient

DEFAULT_UDP_PORT = 5000
"""The OpenFACS UDP port of ``mien serve`` (its ``--udp-port`` default)."""

DEFAULT_HTTP_PORT = 8000
"""The HTTP and WebSocket port of ``mien serve`` (its ``--http-port`` default)."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "send",
        help="send AUs, an emotion, PAD or a laugh to a running server",
        description="Send one message to `mien serve`: the full AU state (--au, missing AUs are 0, as in "
        "OpenFACS), an emotion event, a PAD state or a laugh. UDP to --udp-port by default: UDP has no reply, so "
        "nothing confirms delivery unless --check asks the server over HTTP (--http-port). --ws sends it over the "
        "WebSocket on --http-port and reports the frame that shows it.",
    )
    parser.add_argument("--au", action="append", metavar="AU=INTENSITY", help="e.g. AU12=3 or AU6L=1.5 (repeatable)")
    parser.add_argument("--speed", type=float, help="OpenFACS Speed 0..1 per tick at 60 Hz (default 0.05 with --au)")
    parser.add_argument("--emotion", help="emotion or blend name (joy, sadness, ..., furious)")
    parser.add_argument("--laugh", help="laugh or smile type (e.g. laughter)")
    parser.add_argument("--intensity", type=float, default=1.0, help="intensity of --emotion / --laugh, 0..5")
    parser.add_argument("--pad", nargs=3, type=float, metavar=("P", "A", "D"), help="PAD state, each -1..1")
    parser.add_argument("--character", metavar="ID", help="target character (default: the server's first)")
    parser.add_argument("--host", default="127.0.0.1", help="server address (default %(default)s)")
    parser.add_argument(
        "--udp-port", type=int, metavar="PORT", help=f"the server's OpenFACS UDP port (default {DEFAULT_UDP_PORT})"
    )
    parser.add_argument(
        "--http-port",
        type=int,
        metavar="PORT",
        help=f"the server's HTTP + WebSocket port, with --ws or --check (default {DEFAULT_HTTP_PORT})",
    )
    parser.add_argument("--ws", action="store_true", help="send over the WebSocket instead of UDP")
    parser.add_argument(
        "--check",
        action="store_true",
        help="verify through the HTTP API: the character exists before sending, and the server accepted the "
        "message after (exit 2 with the reason when not)",
    )
    old_port = add_deprecated_option(parser, "--port", "--udp-port, or --http-port with --ws", type=int, metavar="PORT")

    def take_port(args: argparse.Namespace) -> None:
        """The old ``--port`` meant the UDP port, or the HTTP port with ``--ws``: keep that meaning."""
        port = getattr(args, old_port)
        if port is None:
            return
        new = "--http-port" if args.ws else "--udp-port"
        if getattr(args, new.lstrip("-").replace("-", "_")) is not None:
            parser.error(f"--port {port} and {new} both name the port: give {new} only")
        setattr(args, new.lstrip("-").replace("-", "_"), port)

    parser.set_defaults(_finish_port=take_port)
    add_token(parser, help="access token (--ws or --check to a server beyond loopback)")
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
    if args.ws and args.udp_port is not None:
        raise InvalidValueError("--udp-port", args.udp_port, "no --udp-port with --ws: the WebSocket is on --http-port")
    if not args.ws and not args.check and args.http_port is not None:
        raise InvalidValueError("--http-port", args.http_port, "--ws as well, or --check (UDP goes to --udp-port)")
    for option, port in (("--udp-port", args.udp_port), ("--http-port", args.http_port)):
        if port is not None and not 0 < port <= 65535:
            raise InvalidValueError(option, port, "a port 1..65535")
    http_port = DEFAULT_HTTP_PORT if args.http_port is None else args.http_port
    server = _check_character(args, http_port) if args.check else None
    if not args.ws:
        from mien.client import UdpClient, openfacs_message

        udp_port = DEFAULT_UDP_PORT if args.udp_port is None else args.udp_port
        before = server.health() if server is not None else None
        with UdpClient(args.host, udp_port) as client:
            if args.au or args.speed is not None:
                aus = {k: v for k, v in message.items() if k.startswith("AU")}
                rest = {k: v for k, v in message.items() if not k.startswith("AU") and k != "Speed"}
                client.send_raw(openfacs_message(aus, message["Speed"], **rest))  # type: ignore[arg-type]
            else:
                client.send_raw(data)
        where = f"udp://{args.host}:{udp_port}"
        if server is None or before is None:
            print(
                f"sent {len(data)} bytes to {where} (UDP has no reply: nothing confirms that the server got it or "
                "took it; --check asks the server over HTTP)"
            )
            return 0
        _check_delivery(server, before, where)
        print(f"sent {len(data)} bytes to {where}; the server accepted it (checked over {server.base_url})")
        return 0
    from mien.client import WebSocketClient

    url = f"ws://{args.host}:{http_port}/ws"
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


def _check_character(args: argparse.Namespace, http_port: int) -> HttpClient:
    """The server's HTTP client once ``--character`` (or a default character) is known to exist there."""
    from mien.client import HttpClient
    from mien.errors import InvalidValueError

    host = f"[{args.host}]" if ":" in args.host else args.host
    server = HttpClient(f"http://{host}:{http_port}", token=args.token)
    ids = server.characters()
    if not ids:
        raise InvalidValueError("--check", server.base_url, "a server with at least one character")
    if args.character is not None and args.character not in ids:
        raise InvalidValueError("--character", args.character, f"a character of {server.base_url}: {', '.join(ids)}")
    return server


def _check_delivery(server: HttpClient, before: dict[str, Any], where: str, wait_s: float = 2.0) -> None:
    """Wait (at most ``wait_s``) until the server's counters show the datagram accepted; raise when it was
    refused (naming the reason) or never came."""
    import time

    from mien.errors import MienError

    deadline = time.monotonic() + wait_s
    while True:
        now = server.health()
        refused = {
            reason: count - before["rejections"].get(reason, 0)
            for reason, count in now["rejections"].items()
            if count > before["rejections"].get(reason, 0)
        }
        if refused:
            reasons = ", ".join(f"{reason} ({count})" for reason, count in sorted(refused.items()))
            raise MienError(f"the server at {where} refused the message: {reasons}; see its log for the value")
        if now["datagrams_accepted"] > before["datagrams_accepted"]:
            return
        if time.monotonic() > deadline:
            raise MienError(
                f"the server behind {server.base_url} received nothing on {where} in {wait_s:g} s: is --udp-port "
                "its UDP port (mien serve prints it), and does no firewall drop UDP?"
            )
        time.sleep(0.05)
