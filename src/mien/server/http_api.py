"""The HTTP API (FastAPI; its OpenAPI description is at ``/openapi.json``) and the ``/ws`` route.

Every command goes through the same parser as UDP and WebSocket messages
(:func:`mien.server.protocol.parse_message`), so the three transports accept exactly the same things.
"""

from __future__ import annotations

import asyncio
import secrets
import time
from typing import Any
from urllib.parse import quote

import orjson
from fastapi import Depends, FastAPI, HTTPException, Query, Request, Response, WebSocket, status
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse
from pydantic import BaseModel, ConfigDict, Field

from mien.errors import MienError, UnknownNameError
from mien.exchange.glb import head_glb_bytes
from mien.server.guard import AccessPolicy, BodyTooLarge, BodyTooSlow, Guard, access_policy, read_body
from mien.server.head_view import MEDIA_TYPES, referenced_files
from mien.server.protocol import MAX_SAY_CHARS, MessageRejected, frame_bytes, idle_parts, parse_message
from mien.server.registry import CharacterSpec, Entry
from mien.server.running import RunningServer
from mien.server.uploads import BODY_TIMEOUT_S, MAX_CLIP_BYTES, Uploads, UploadsBusy, check_suffix
from mien.viewer import routes

__all__ = ["create_app"]

_MAX_COMMAND_BYTES = 8192


class _Body(BaseModel):
    """A request body: unknown fields and NaN or infinite numbers are refused (422, naming the field)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class Health(BaseModel):
    """Server health and counters."""

    status: str = Field(description='"ok", or "degraded" while ticks fail or run late or a character is quarantined')
    degraded: list[str] = Field(
        description="Why degraded: tick_errors, late_ticks, stalled, quarantined, capture_failed"
    )
    quarantined: dict[str, str] = Field(description="Characters taken out because stepping them failed: id -> why")
    step_failures: int = Field(description="Ticks whose step failed (a character was quarantined)")
    datagrams_dropped_by_os: int | None = Field(description="UDP datagrams the OS dropped (full queue; null: unknown)")
    viewers_refused: int = Field(description="WebSocket viewers refused past max_viewers (close code 1013)")
    frames_thinned: int = Field(description="Frames not sent to viewers because the clock ran late")
    frame_stride: int = Field(description="Viewers get every frame_stride-th tick's frame (1; more while late)")
    max_viewers: int = Field(description="Most WebSocket viewers served at once")
    uptime_s: float = Field(description="Seconds since the server started")
    tick_hz: float = Field(description="Clock rate, ticks per second")
    ticks: int = Field(description="Ticks run")
    late_ticks: int = Field(description="Ticks that overran their budget")
    skipped_ticks: int = Field(description="Ticks skipped to catch up after a stall")
    tick_errors: int = Field(description="Ticks that raised (logged)")
    max_tick_cost_ms: float = Field(description="Largest tick work time, milliseconds")
    datagrams_received: int = Field(description="UDP datagrams received")
    datagrams_accepted: int = Field(description="UDP datagrams parsed and queued")
    ws_commands_accepted: int = Field(description="WebSocket commands parsed and queued")
    http_commands: int = Field(description="Commands accepted over HTTP")
    coalesced: int = Field(description="State messages superseded before a tick applied them")
    rejections: dict[str, int] = Field(description="Dropped messages per reason")
    viewers: int = Field(description="Connected WebSocket viewers")
    characters: int = Field(description="Number of characters")
    frames_sent: int = Field(description="WebSocket frames handed to viewers")
    frames_dropped: int = Field(description="Frames replaced before a slow viewer read them")
    capture: str | None = Field(
        None, description="State of the capture source (tracking, no_face, ended, failed...; null: none)"
    )


class CaptureTiming(BaseModel):
    """One tracked frame of the capture source, on the server's ``time.monotonic()`` clock (seconds)."""

    frame: int = Field(description="Number of the tracked frame")
    source_s: float = Field(description="Its time in the source: a video's time stamp (+ earlier loops), seconds")
    arrival_s: float = Field(description="When the frame arrived (read from the camera, or its time came due)")
    track_start_s: float = Field(description="When the tracker took it")
    tracked_s: float = Field(description="When its face frame was ready")
    tick: int | None = Field(description="First tick that showed it (null: not yet, or no character follows)")


class CaptureStatus(BaseModel):
    """The capture source (``mien serve --capture``)."""

    source: str = Field(description="Camera device or video file")
    kind: str = Field(description="camera or file")
    loop: bool = Field(description="A video file starts again at its end")
    state: str = Field(description="starting, tracking, no_face, ended, failed or stopped")
    error: str | None = Field(description="Why it failed")
    has_face: bool = Field(description="The newest tracked frame has a face")
    followers: list[str] = Field(description="Characters that follow it")
    frames_read: int
    frames_tracked: int
    frames_dropped: int = Field(description="Frames replaced by a newer one while the tracker was busy")
    frames_without_face: int
    frames_face_too_small: int = Field(description="Frames whose face was narrower than min_face_px (no face)")
    tracking_ms: float | None = Field(description="Median tracking time of the recent frames, ms")
    tracking_p99_ms: float | None = Field(description="99th percentile of the recent frames' tracking time, ms")
    timings: list[CaptureTiming] = Field(description="The newest tracked frames' timings")


class CaptureCommand(_Body):
    """Follow the capture source or stop."""

    follow: bool = Field(description="true: the character's face follows the performer; false: it stops")


class CharacterCreate(_Body):
    """A new character."""

    id: str = Field(pattern=r"^[A-Za-z0-9_.\-]{1,64}$", description="Character id")
    head: str = Field(
        "default", description="Head: default, builtin, ict, or a head file on the server (face.glb, file:PATH)"
    )
    identity: str | None = Field(None, description="Identity preset of the head (null = default)")
    seed: int = Field(0, description="Seed of idle behaviour and laughter")
    idle: bool = Field(True, description="Idle behaviour on or off")
    expression_basis: str = Field("facs", description="facs or feature_points")


class CharacterInfo(BaseModel):
    """A character."""

    id: str
    row: int = Field(description="Row in the server's batch (the frame's character row)")
    head: str
    identity: str | None
    seed: int
    idle: bool = Field(description="Any idle behaviour on")
    idle_parts: dict[str, bool] = Field(description="Each idle switch")
    expression_basis: str
    target_names: list[str] = Field(
        description="Morph targets, in frame weight order (a head file shown as itself: the file's own shape names)"
    )
    frame_bytes: int = Field(description="Bytes of one WebSocket frame of this character")
    head_url: str = Field(description="Where a viewer loads the head's glTF (the user's own file for a head file)")
    head_file: str | None = Field(description="Name of the user's head file served as is (null: mien's glTF)")
    file_to_rig: list[float] | None = Field(
        description="Head file: 4x4 row-major similarity from the file's coordinates to mien's frame (metres, "
        "origin between the eyes, +y up, +z forward); null otherwise"
    )
    head_note: str = Field(
        description="Why a head file is shown as mien's glTF, or which synthesized shapes its file view leaves out"
    )


class CharacterState(BaseModel):
    """A character's face at the last tick."""

    id: str
    tick: int
    time_s: float = Field(description="Server clock, seconds")
    aus: dict[str, float] = Field(description="AU channel intensities 0..5")
    pose_deg: dict[str, float] = Field(description="Head and gaze angles, degrees")
    weights: dict[str, float] = Field(description="Morph target weights 0..1")


class AusCommand(_Body):
    """Full AU state (AUs not named go to 0), as in an OpenFACS datagram."""

    aus: dict[str, float] = Field(description='AU -> intensity 0..5, e.g. {"AU12": 3, "AU6L": 1.5}')
    speed: float | None = Field(None, description="OpenFACS Speed 0..1 per tick at 60 Hz")
    speeds: dict[str, float] | None = Field(None, description="Per-AU speed 0..1")
    tau_s: dict[str, float] | None = Field(None, description="Per-AU time constant, seconds")


class EmotionCommand(_Body):
    """An emotion or blend event."""

    emotion: str = Field(description="joy, sadness, anger, surprise, disgust, fear, a blend or an alias")
    intensity: float = Field(1.0, description="0..5; 1 = the prototype")


class PadCommand(_Body):
    """A PAD (pleasure, arousal, dominance) state, each -1..1."""

    pleasure: float
    arousal: float
    dominance: float


class LaughterCommand(_Body):
    """A laugh or smile."""

    type: str = Field(description="One of the 13 laugh and smile types, e.g. laughter")
    intensity: float = Field(1.0, description="0..5")


class IdleCommand(_Body):
    """Idle behaviour switches; ``on`` sets every part, the named parts override it; parts not given keep their
    state."""

    on: bool | None = Field(None, description="Every idle part on or off")
    blink: bool | None = None
    mouth: bool | None = None
    eyelids: bool | None = None
    neck: bool | None = None
    gaze: bool | None = None
    wobble: bool | None = None


class SayCommand(_Body):
    """Text to speak (espeak-ng, off the clock); the utterance starts at the first tick after it is spoken."""

    text: str = Field(description=f"What to say, 1..{MAX_SAY_CHARS} characters")
    language: str = Field("en", description="espeak-ng voice: en, en-us, de, fr...")
    rate_wpm: int = Field(175, description="Speaking rate, words per minute (80..450)")


class SpeechInfo(BaseModel):
    """An utterance a character started (its sound at ``url``)."""

    id: int = Field(description="Number of the utterance")
    character: str
    url: str = Field(description="Its sound, a WAV file")
    start_s: float = Field(description="Server time of its first sample, seconds (the frames' time_s clock)")
    duration_s: float = Field(description="Seconds of speech")
    text: str


class Accepted(BaseModel):
    """A command was queued for the next tick."""

    queued: bool = True
    character: str


class ErrorBody(BaseModel):
    """An error."""

    detail: str


_ERRORS: dict[int | str, dict[str, Any]] = {
    400: {"model": ErrorBody, "description": "Bad input (names the value)"},
    401: {"model": ErrorBody, "description": "Missing or wrong access token"},
    403: {"model": ErrorBody, "description": "Host or Origin not allowed (see docs/SERVER.md, Security)"},
    404: {"model": ErrorBody, "description": "No such character"},
    408: {"model": ErrorBody, "description": "The body did not arrive in time"},
    413: {"model": ErrorBody, "description": "The body is over its size limit"},
    415: {"model": ErrorBody, "description": "Wrong Content-Type (application/json; a clip: application/octet-stream)"},
}
_UPLOAD_ERRORS: dict[int | str, dict[str, Any]] = {
    503: {"model": ErrorBody, "description": "Too many uploads being read; retry (Retry-After)"},
}


def _head_url(entry: Entry) -> str:
    base = f"/api/characters/{quote(entry.spec.id)}"
    source = entry.view.source if entry.view is not None else None
    if source is not None and source.suffix.lower() == ".gltf":
        return f"{base}/head/{quote(source.name)}"  # its buffers and images resolve beside it
    return f"{base}/head.glb"


def _info(entry: Entry) -> CharacterInfo:
    spec = entry.spec
    view = entry.view
    names = list(view.frame_names if view is not None else entry.rig.target_names)
    file_to_rig = view.file_to_rig if view is not None and view.source is not None else None
    return CharacterInfo(
        id=spec.id,
        row=entry.row,
        head=spec.head,
        identity=spec.identity,
        seed=spec.seed,
        idle=entry.idle is not None,
        idle_parts={part: bool(entry.idle is not None and getattr(entry.idle, part)) for part in idle_parts()},
        expression_basis=spec.expression_basis,
        target_names=names,
        frame_bytes=frame_bytes(len(names)),
        head_url=_head_url(entry),
        head_file=view.source.name if view is not None and view.source is not None else None,
        file_to_rig=file_to_rig.ravel().tolist() if file_to_rig is not None else None,
        head_note=view.note if view is not None else "",
    )


def create_app(server: RunningServer, access: AccessPolicy | None = None) -> FastAPI:
    """The FastAPI app of ``server``, with the browser viewer (:func:`mien.viewer.routes.mount`).

    Every request passes :class:`mien.server.guard.Guard` first: ``Host`` and ``Origin`` checked against
    ``access`` (default: a loopback server's, no other origin), content types, body size and time limits.

    The handlers that read or change the characters are ``async``: they run on the event loop, between ticks,
    never in a worker thread beside the clock. Loading a new character's head runs in a thread.
    """
    app = FastAPI(
        docs_url=None,  # Swagger UI and ReDoc load their scripts from a CDN; mien never downloads at run time
        redoc_url=None,
        title="mien live",
        version="1",
        description="Drive virtual characters' faces: AUs (OpenFACS), emotions, PAD, laughter. "
        "The WebSocket stream is at /ws?character=ID (binary frames, see docs/SERVER.md).",
    )
    registry = server.registry
    policy = access if access is not None else access_policy("127.0.0.1")
    if policy.origins:  # pages of an allowed origin may call the API (their preflight requests get an answer)
        from starlette.middleware.cors import CORSMiddleware

        app.add_middleware(
            CORSMiddleware, allow_origins=sorted(policy.origins), allow_methods=["*"],
            allow_headers=["authorization", "content-type"],
        )  # fmt: skip
    app.add_middleware(Guard, policy=policy)  # outermost: before CORS and every route
    uploads = Uploads()

    def check_token(request: Request) -> None:
        if server.token is None:
            return
        header = request.headers.get("authorization", "")
        given = header[7:] if header.lower().startswith("bearer ") else request.query_params.get("token", "")
        if not secrets.compare_digest(given.encode(), server.token.encode()):
            raise HTTPException(status.HTTP_401_UNAUTHORIZED, "missing or wrong access token (Bearer or ?token=)")

    @app.exception_handler(RequestValidationError)
    async def _invalid_body(request: Request, exc: RequestValidationError) -> JSONResponse:
        # FastAPI's own answer echoes the input, and a NaN in it cannot be written as JSON (a 500): name the field,
        # say what is wrong, leave the value out
        detail = [{"loc": list(error["loc"]), "msg": error["msg"], "type": error["type"]} for error in exc.errors()]
        return JSONResponse({"detail": detail}, status_code=422)

    @app.exception_handler(MienError)
    async def _mien_error(request: Request, exc: MienError) -> JSONResponse:
        code = 404 if isinstance(exc, UnknownNameError) and exc.kind == "character" else 400
        return JSONResponse({"detail": str(exc)}, status_code=code)

    def entry_of(character_id: str) -> Entry:
        return registry.get(character_id)

    def queue(character_id: str, command: dict[str, Any]) -> Accepted:
        entry = entry_of(character_id)
        command["character"] = entry.spec.id
        try:
            message = parse_message(orjson.dumps(command), max_bytes=_MAX_COMMAND_BYTES)
            registry.submit(message)
        except MessageRejected as exc:
            registry.reject(exc)
            raise HTTPException(status.HTTP_400_BAD_REQUEST, str(exc)) from None
        registry.counters.http_commands += 1
        return Accepted(character=entry.spec.id)

    api = [Depends(check_token)]

    @app.get("/api/health", response_model=Health, dependencies=api, responses=_ERRORS)
    async def health() -> Health:
        """Uptime, clock, message and viewer counters, rejections per reason."""
        c, s = registry.counters, server.clock.stats
        return Health(
            **server.health_state(),
            uptime_s=time.monotonic() - server.started_monotonic,
            tick_hz=server.clock.tick_hz,
            ticks=s.ticks,
            late_ticks=s.late_ticks,
            skipped_ticks=s.skipped_ticks,
            tick_errors=s.tick_errors,
            max_tick_cost_ms=s.max_tick_cost_s * 1e3,
            datagrams_received=c.datagrams_received,
            datagrams_accepted=c.datagrams_accepted,
            ws_commands_accepted=c.ws_commands_accepted,
            http_commands=c.http_commands,
            coalesced=c.coalesced,
            rejections=dict(c.rejections),
            viewers=len(server.hub.viewers),
            characters=len(registry.entries),
            frames_sent=c.frames_sent,
            frames_dropped=c.frames_dropped,
            capture=registry.capture.state if registry.capture is not None else None,
        )

    @app.get("/api/characters", response_model=list[CharacterInfo], dependencies=api, responses=_ERRORS)
    async def list_characters() -> list[CharacterInfo]:
        """Every character, in creation order (the first is the default target)."""
        return [_info(entry) for entry in registry.entries.values()]

    @app.post("/api/characters", response_model=CharacterInfo, status_code=201, dependencies=api, responses=_ERRORS)
    async def create_character(body: CharacterCreate) -> CharacterInfo:
        """Create a character with its own head, identity, seed, idle and emotion settings."""
        spec = CharacterSpec(**body.model_dump())
        await asyncio.to_thread(registry.prepare, spec)  # the slow head load stays off the clock
        return _info(registry.add(spec))

    @app.get("/api/characters/{character_id}", response_model=CharacterState, dependencies=api, responses=_ERRORS)
    async def character_state(character_id: str) -> CharacterState:
        """The character's face at the last tick: AUs, pose and morph weights."""
        entry = entry_of(character_id)
        state = registry.state(entry)
        weights = registry.rig_output(entry)[0].tolist() if entry.row < registry.frames.shape[0] else []
        au_names = [name for name in state if name.startswith("AU")]
        return CharacterState(
            id=entry.spec.id,
            tick=server.clock.tick,
            time_s=registry.time_s,
            aus={name: state[name] for name in au_names},
            pose_deg={name: value for name, value in state.items() if not name.startswith("AU")},
            weights={name: float(w) for name, w in zip(entry.rig.target_names, weights, strict=False)},
        )

    @app.delete("/api/characters/{character_id}", status_code=204, dependencies=api, responses=_ERRORS)
    async def delete_character(character_id: str) -> Response:
        """Remove a character (its viewers get no more frames)."""
        registry.remove(character_id)
        return Response(status_code=204)

    @app.post("/api/characters/{character_id}/aus", response_model=Accepted, status_code=202, dependencies=api,
              responses=_ERRORS)  # fmt: skip
    async def send_aus(character_id: str, body: AusCommand) -> Accepted:
        """Set the full AU state (AUs not named go to 0) with an optional OpenFACS Speed."""
        command: dict[str, Any] = dict(body.aus)
        if body.speed is not None:
            command["Speed"] = body.speed
        if body.speeds:
            command["speeds"] = body.speeds
        if body.tau_s:
            command["tau_s"] = body.tau_s
        if not command:
            command["AU1"] = 0.0  # an empty state still means "every AU to 0"
        return queue(character_id, command)

    @app.post("/api/characters/{character_id}/emotion", response_model=Accepted, status_code=202,
              dependencies=api, responses=_ERRORS)  # fmt: skip
    async def send_emotion(character_id: str, body: EmotionCommand) -> Accepted:
        """Trigger an emotion or blend event now."""
        return queue(character_id, {"emotion": body.emotion, "intensity": body.intensity})

    @app.post("/api/characters/{character_id}/pad", response_model=Accepted, status_code=202, dependencies=api,
              responses=_ERRORS)  # fmt: skip
    async def send_pad(character_id: str, body: PadCommand) -> Accepted:
        """Move the PAD state (each -1..1)."""
        return queue(character_id, {"pad": [body.pleasure, body.arousal, body.dominance]})

    @app.post("/api/characters/{character_id}/laughter", response_model=Accepted, status_code=202,
              dependencies=api, responses=_ERRORS)  # fmt: skip
    async def send_laughter(character_id: str, body: LaughterCommand) -> Accepted:
        """Play a laugh or smile now."""
        return queue(character_id, {"laugh": body.type, "intensity": body.intensity})

    @app.post("/api/characters/{character_id}/idle", response_model=Accepted, status_code=202, dependencies=api,
              responses=_ERRORS)  # fmt: skip
    async def send_idle(character_id: str, body: IdleCommand) -> Accepted:
        """Switch idle behaviour (blinks, mouth and eyelid micro-motion, neck, gaze, wobble) on or off."""
        switches: dict[str, bool] = dict.fromkeys(idle_parts(), body.on) if body.on is not None else {}
        switches.update({part: on for part in idle_parts() if (on := getattr(body, part)) is not None})
        return queue(character_id, {"idle": switches})

    @app.post("/api/characters/{character_id}/capture", response_model=Accepted, status_code=202,
              dependencies=api, responses=_ERRORS)  # fmt: skip
    async def send_capture(character_id: str, body: CaptureCommand) -> Accepted:
        """Make the character follow the capture source (a second character mirrors the first) or stop."""
        return queue(character_id, {"capture": body.follow})

    @app.post("/api/characters/{character_id}/say", response_model=Accepted, status_code=202, dependencies=api,
              responses=_ERRORS)  # fmt: skip
    async def send_say(character_id: str, body: SayCommand) -> Accepted:
        """Speak ``text`` (espeak-ng in a worker thread, so the clock never waits); the character starts at the
        first tick after, and its viewers are told where the sound is (docs/SERVER.md, Speech)."""
        return queue(character_id, {"say": body.model_dump()})

    @app.get("/api/characters/{character_id}/speech", response_model=SpeechInfo, dependencies=api,
             responses=_ERRORS)  # fmt: skip
    async def character_speech(character_id: str) -> SpeechInfo:
        """The utterance the character is saying or about to say (404: silent)."""
        entry = entry_of(character_id)
        spoken = registry.speech.playing(entry.spec.id, registry.time_s)
        if spoken is None:
            raise HTTPException(404, f"{entry.spec.id} is not speaking")
        return SpeechInfo(**spoken.announcement()["speech"])

    @app.get("/api/speech/{utterance_id}.wav", dependencies=api,
             responses={**_ERRORS, 200: {"content": {"audio/wav": {}}}})  # fmt: skip
    async def speech_sound(utterance_id: int) -> Response:
        """The sound of utterance ``utterance_id`` (one of the newest 32), a 16-bit PCM mono WAV."""
        spoken = registry.speech.get(utterance_id)
        if spoken is None:
            raise HTTPException(404, f"no utterance {utterance_id} (only the newest are kept)")
        return Response(spoken.wav, media_type="audio/wav")

    @app.get("/api/capture", response_model=CaptureStatus, dependencies=api, responses=_ERRORS)
    async def capture_status() -> CaptureStatus:
        """The capture source: state, counters, tracking time and the newest frames' timings (404: none)."""
        source = registry.capture
        if source is None:
            raise HTTPException(404, "this server has no capture source (mien serve --capture)")
        followers = [entry.spec.id for entry in registry.entries.values() if entry.performance is source]
        return CaptureStatus(**source.status(), followers=followers)

    @app.post("/api/characters/{character_id}/clip", response_model=Accepted, status_code=202, dependencies=api,
              responses={**_ERRORS, **_UPLOAD_ERRORS}, openapi_extra={"requestBody": {"required": True, "content": {
                  "application/octet-stream": {"schema": {"type": "string", "format": "binary"}}}}})  # fmt: skip
    async def send_clip(
        character_id: str, request: Request, suffix: str = Query(description="File suffix, e.g. .json or .npz")
    ) -> Accepted:
        """Play a clip file (its bytes as the body, ``Content-Type: application/octet-stream``; ``suffix`` picks
        the reader) on the character now. The file is read in a worker process with size and time limits
        (``mien.server.uploads``): the clock never waits for it."""
        entry_of(character_id)
        check_suffix(suffix)
        declared = request.headers.get("content-length", "")
        try:
            with uploads.slot():
                data = await read_body(
                    request.receive, MAX_CLIP_BYTES, BODY_TIMEOUT_S, int(declared) if declared.isdigit() else None
                )
                clip = await uploads.read(data, suffix)
        except UploadsBusy as exc:
            raise HTTPException(503, str(exc), headers={"Retry-After": "1"}) from None
        except BodyTooLarge as exc:
            raise HTTPException(413, f"clip: {exc}", headers={"Connection": "close"}) from None
        except BodyTooSlow as exc:
            raise HTTPException(408, f"clip: {exc}", headers={"Connection": "close"}) from None
        entry = entry_of(character_id)  # it may have gone while the file was read
        entry.clips.append(clip)
        registry.counters.http_commands += 1
        return Accepted(character=entry.spec.id)

    @app.get("/api/characters/{character_id}/head.glb", dependencies=api,
             responses={**_ERRORS, 200: {"content": {"model/gltf-binary": {}}}})  # fmt: skip
    def head_glb(character_id: str) -> Response:
        """The character's head as glTF binary: mien's glTF of the rig (mesh and morph targets in frame weight
        order), or the user's own ``.glb``/``.vrm`` file as is (its frames name their weights in
        ``target_names``); a ``.gltf`` head file redirects to its ``head_url``."""
        entry = entry_of(character_id)
        source = entry.view.source if entry.view is not None else None
        if source is None:
            return Response(head_glb_bytes(entry.rig), media_type="model/gltf-binary")
        if source.suffix.lower() == ".gltf":
            return RedirectResponse(_head_url(entry), status_code=307)
        return FileResponse(source, media_type=entry.view.media_type if entry.view else None)

    @app.get("/api/characters/{character_id}/head/{path:path}", dependencies=api, responses=_ERRORS)
    def head_file(character_id: str, path: str) -> Response:
        """A ``.gltf`` head file (``head_url``) and the buffers and images it points at, by their relative URIs."""
        entry = entry_of(character_id)
        source = entry.view.source if entry.view is not None else None
        if source is None or source.suffix.lower() != ".gltf":
            raise HTTPException(404, f"{character_id}'s head is no .gltf file")
        if path == source.name:
            return FileResponse(source, media_type=MEDIA_TYPES[".gltf"])
        found = referenced_files(source).get(path)
        if found is None:
            raise HTTPException(404, f"{path!r} is not a file {source.name} points at")
        return FileResponse(found, media_type=MEDIA_TYPES.get(found.suffix.lower(), "application/octet-stream"))

    @app.websocket("/ws")
    async def stream(websocket: WebSocket, character: str | None = None, token: str | None = None) -> None:
        """Binary frames of ``character`` (default: the first) each tick; JSON commands the other way."""
        if server.token is not None and not secrets.compare_digest((token or "").encode(), server.token.encode()):
            await websocket.close(code=1008, reason="missing or wrong access token (?token=)")
            return
        if character is not None and character not in registry.entries:
            await websocket.close(code=1008, reason=f"unknown character {character!r}")
            return
        await websocket.accept()
        await server.hub.serve(websocket, character)

    routes.mount(app)
    return app
