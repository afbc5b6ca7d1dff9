"""The web experiment: a FastAPI app serving the pages (``static/``), the stimulus videos and a small JSON API.

Flow for a participant opening ``/?participant=ID`` (an id is generated when absent): consent ->
instructions -> one stimulus at a time (the video plays once, "Play again" replays it, every play counted as
nrShows) with the protocol's questions -> next -> completion page (code and/or redirect). Each answer is
POSTed and committed at once (:meth:`mien.study.storage.Store.record_answer`); reopening the link resumes at
the first unanswered stimulus. Everything is served by the app itself: it works with no internet.

API (JSON):

- ``POST /api/session {"participant": ID | null}`` -> the participant's plan and progress (created on first
  arrival: label order seeded by the id, within-subject blocks from the balanced Latin square).
- ``POST /api/consent {"participant"}``
- ``POST /api/show {"participant", "stimulus", "nr_shows"}`` -> the stored play count (idempotent: max).
- ``POST /api/answer {"participant", "stimulus", "position", "ratings": {question: int}, "nr_shows"}`` ->
  ``{"stored": new rows, "next_position", "done", ...}``; a repeated submit stores nothing twice. Answers come
  in the participant's order (a position after the first unanswered one is refused, 409) and only for a
  stimulus that was shown (``nr_shows`` >= 1 here or from ``/api/show``; else 422).
- ``GET /api/health`` -> ``{"status": "ok" | "degraded", "database": ..., ...}``: degraded while the
  database is locked or unreachable.

Bad requests get 4xx with a message naming the value; a locked or unreachable database gets 503 with
``Retry-After`` once the store's bound (``busy_timeout_s``) is spent (the page retries); the server never
dies of a request.
"""

# No ``from __future__ import annotations``: FastAPI reads the request models of the endpoints (classes local
# to create_app) from the evaluated annotations.

import contextlib
import math
import re
import secrets
import socket
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from mien.errors import InvalidValueError
from mien.extras import require
from mien.study.design import check_redirect_url
from mien.study.protocol import participant_plan, questions
from mien.study.storage import StorageUnavailableError

if TYPE_CHECKING:
    from fastapi import FastAPI

    from mien.study.design import Design
    from mien.study.storage import ParticipantRecord, Store

__all__ = ["PARTICIPANT_PATTERN", "create_app", "listen", "serve"]

STATIC = Path(__file__).with_name("static")
"""The pages: index.html, study.js, study.css."""

PARTICIPANT_PATTERN = re.compile(r"^[A-Za-z0-9_.@:-]{1,128}$")
"""Accepted participant ids (recruitment platforms' ids fit: letters, digits, ``_ . @ : -``, up to 128)."""

WORKER_THREADS = 8
"""Threads running the (blocking, database) endpoints. Few on purpose: more threads than cores only contend
for the GIL and starve the event loop; extra requests wait their turn on the loop instead."""

BUILTIN_CONSENT = (
    "This study shows short videos of a virtual character's face and asks how you perceive them. Taking part "
    "is voluntary; you can stop at any time by closing the page, and you can come back to the same link to "
    "continue. Your answers are stored under your participant id only, with no other personal data."
)
"""Consent text used when the design gives none."""

BUILTIN_INSTRUCTIONS = {
    "broekens": "You will see short videos of a virtual character's face, one at a time. Each plays once; use "
    '"Play again" as often as you need. Then rate how much the face expresses each emotion (1 = not at all, 5 = '
    "very) and how natural the expression looks (1..5), and press Next.",
    "mascaro": "You will see short videos of a virtual character laughing or smiling, one at a time, with a "
    'description of the expression. Use "Play again" as often as you need. Answer both questions from 0 (not '
    "at all) to 5 (completely) and press Next.",
}
"""Instructions per protocol used when the design gives none."""


def create_app(design: "Design", manifest: dict[str, Any], stimuli_folder: str | Path, store: "Store") -> "FastAPI":
    """The experiment app for ``design`` with the stimuli of ``manifest`` (served from ``stimuli_folder``),
    storing into ``store`` (whose stimuli table should hold the manifest: :meth:`Store.register_stimuli`)."""
    require("fastapi", "study")
    from fastapi import FastAPI, HTTPException, Request
    from fastapi.responses import FileResponse, JSONResponse, Response
    from fastapi.staticfiles import StaticFiles
    from pydantic import BaseModel, Field

    folder = Path(stimuli_folder).resolve()
    entries = {entry["id"]: entry for entry in manifest["stimuli"]}
    files = {entry["file"] for entry in manifest["stimuli"]}
    asked = {q.key: q for q in questions(design.protocol)}
    study = design.name
    plans: dict[str, ParticipantRecord] = {}
    check_redirect_url(design.redirect_url, "redirect_url")  # a Design built in code passes here too
    retry_after = str(max(1, math.ceil(store.busy_timeout_s)))

    class SessionRequest(BaseModel):
        participant: str | None = Field(default=None, max_length=128)

    class ConsentRequest(BaseModel):
        participant: str = Field(max_length=128)

    class ShowRequest(BaseModel):
        participant: str = Field(max_length=128)
        stimulus: str = Field(max_length=64)
        nr_shows: int = Field(ge=1, le=10_000)

    class AnswerRequest(BaseModel):
        participant: str = Field(max_length=128)
        stimulus: str = Field(max_length=64)
        position: int = Field(ge=0)
        ratings: dict[str, int]
        nr_shows: int = Field(ge=0, le=10_000)

    @contextlib.asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        import anyio.to_thread

        anyio.to_thread.current_default_thread_limiter().total_tokens = WORKER_THREADS
        yield

    app = FastAPI(title=f"mien study: {study}", docs_url=None, redoc_url=None, lifespan=lifespan)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")

    @app.exception_handler(StorageUnavailableError)
    async def _unavailable(_request: Request, error: StorageUnavailableError) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=503, headers={"Retry-After": retry_after})

    def record(participant: str) -> "ParticipantRecord":
        if not PARTICIPANT_PATTERN.fullmatch(participant):
            raise HTTPException(
                422, f"participant {participant!r} is invalid: use 1-128 letters, digits or _ . @ : - in ?participant="
            )
        if participant in plans:
            return plans[participant]
        found = store.participant(study, participant)
        if found is None:
            raise HTTPException(404, f"participant {participant!r} has no session: open /?participant=ID first")
        plans[participant] = found
        return found

    def status(rec: "ParticipantRecord", progress: tuple[set[str], dict[str, int]] | None = None) -> dict[str, Any]:
        """The participant's progress for the page (``progress``: :meth:`Store.progress` already read)."""
        answered, shows = store.progress(study, rec.participant) if progress is None else progress
        remaining = [k for k, s in enumerate(rec.sequence) if s not in answered]
        done = not remaining
        if done and rec.completed_at is None:
            store.record_completed(study, rec.participant)
        # the id is quoted so it stays inside its place in the URL (ids may hold ':' and '@')
        redirect = design.redirect_url.replace("{participant}", quote(rec.participant, safe="")) if done else ""
        return {
            "next_position": remaining[0] if remaining else len(rec.sequence),
            "answered": len(rec.sequence) - len(remaining),
            "nr_shows": shows,
            "done": done,
            "completion_code": design.completion_code if done else "",
            "redirect_url": redirect if done else "",
        }

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    @app.get("/favicon.ico", include_in_schema=False)
    def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/api/health")
    async def health() -> dict[str, Any]:  # async: answered on the event loop, no thread hop
        database = store.health()  # what the last operations found; never waits for the database
        status = "ok" if database["database"] == "ok" else "degraded"
        return {"status": status, "study": study, "protocol": design.protocol, "stimuli": len(entries), **database}

    @app.get("/stimuli/{name}")
    def stimulus_file(name: str) -> FileResponse:
        if name not in files:
            raise HTTPException(404, f"stimulus file {name!r} is not in the manifest")
        return FileResponse(folder / name, headers={"Cache-Control": "max-age=3600"})

    @app.post("/api/session")
    def session(request: SessionRequest) -> dict[str, Any]:
        participant = request.participant or secrets.token_hex(6)
        if not PARTICIPANT_PATTERN.fullmatch(participant):
            raise HTTPException(
                422, f"participant {participant!r} is invalid: use 1-128 letters, digits or _ . @ : - in ?participant="
            )

        def plan(ordinal: int) -> tuple[Any, Any, Any]:
            p = participant_plan(design, participant, ordinal)
            return p.sequence, p.label_order, p.block_order

        rec = plans.get(participant) or store.ensure_participant(study, participant, plan)
        plans[participant] = rec
        shown = [
            {
                "key": key,
                "text": asked[key].text,
                "low": asked[key].low,
                "high": asked[key].high,
                "low_text": asked[key].low_text,
                "high_text": asked[key].high_text,
            }
            for key in rec.label_order
        ]
        sequence = [
            {
                "position": k,
                "stimulus": s,
                "url": f"/stimuli/{entries[s]['file']}",
                "description": str(entries[s].get("conditions", {}).get("description", "")),
            }
            for k, s in enumerate(rec.sequence)
        ]
        return {
            "participant": participant,
            "study": study,
            "protocol": design.protocol,
            "consent_given": rec.consent_at is not None,
            "consent_text": design.consent_text or BUILTIN_CONSENT,
            "instructions_text": design.instructions_text or BUILTIN_INSTRUCTIONS[design.protocol],
            "questions": shown,
            "sequence": sequence,
            **status(rec),
        }

    @app.post("/api/consent")
    def consent(request: ConsentRequest) -> dict[str, Any]:
        rec = record(request.participant)
        store.record_consent(study, rec.participant)
        plans.pop(rec.participant, None)
        return {"consent_given": True}

    @app.post("/api/show")
    def show(request: ShowRequest) -> dict[str, Any]:
        rec = record(request.participant)
        if request.stimulus not in rec.sequence:
            raise HTTPException(422, f"stimulus {request.stimulus!r} is not in participant {rec.participant!r}'s set")
        return {"nr_shows": store.record_show(study, rec.participant, request.stimulus, request.nr_shows)}

    @app.post("/api/answer")
    def answer(request: AnswerRequest, response: Response) -> dict[str, Any]:
        start = time.perf_counter()
        rec = record(request.participant)
        if rec.consent_at is None:
            raise HTTPException(409, f"participant {rec.participant!r} has not given consent: POST /api/consent first")
        if request.position >= len(rec.sequence) or rec.sequence[request.position] != request.stimulus:
            raise HTTPException(
                422,
                f"stimulus {request.stimulus!r} is not at position {request.position} of participant "
                f"{rec.participant!r}'s sequence",
            )
        missing = [key for key in rec.label_order if key not in request.ratings]
        extra = [key for key in request.ratings if key not in asked]
        if missing or extra:
            raise HTTPException(
                422, f"ratings must answer exactly {list(rec.label_order)}; missing {missing}, unknown {extra}"
            )
        for key, value in request.ratings.items():
            q = asked[key]
            if not q.low <= value <= q.high:
                raise HTTPException(422, f"rating {key}={value} is invalid: expected an integer {q.low}..{q.high}")
        answered, shows = store.progress(study, rec.participant)
        first_open = next((k for k, s in enumerate(rec.sequence) if s not in answered), len(rec.sequence))
        if request.position > first_open:
            raise HTTPException(
                409,
                f"position {request.position} of participant {rec.participant!r} comes after the unanswered "
                f"position {first_open} ({rec.sequence[first_open]!r}): answer the stimuli in order",
            )
        nr_shows = request.nr_shows or shows.get(request.stimulus, 0)  # the page's count, else the server's
        if nr_shows < 1 and request.stimulus not in answered:
            raise HTTPException(
                422,
                f"nr_shows={request.nr_shows} is invalid: stimulus {request.stimulus!r} was never shown to participant "
                f"{rec.participant!r}; play it (POST /api/show) before rating it",
            )
        label_positions = {key: k for k, key in enumerate(rec.label_order) if asked[key].is_label}
        stored = store.record_answer(
            study,
            rec.participant,
            request.stimulus,
            request.position,
            request.ratings,
            label_positions,
            nr_shows,
        )
        reply = {"stored": stored, **status(rec, (answered | {request.stimulus}, shows))}  # no second read
        # time spent in this handler (validation + commit + progress read), for load tests and monitoring
        response.headers["Server-Timing"] = f"app;dur={(time.perf_counter() - start) * 1000:.2f}"
        return reply

    return app


def listen(host: str = "127.0.0.1", port: int = 8000) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (0 = any free port; read it with ``getsockname()``).

    Raises :class:`~mien.errors.InvalidValueError` naming the port when it is taken or cannot be bound.
    """

    if not 0 <= port <= 65535:
        raise InvalidValueError("--http-port", port, "a TCP port 0..65535")
    sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as error:
        sock.close()
        raise InvalidValueError(
            "--http-port", port, f"a free port on {host} ({error.strerror}); stop the other server or pick another port"
        ) from None
    return sock


def serve(app: "FastAPI", sock: socket.socket) -> None:
    """Run ``app`` with uvicorn on the listening socket ``sock`` (see :func:`listen`) until interrupted."""
    uvicorn = require("uvicorn", "study")
    # keep-alive longer than a participant's time per stimulus, so the browser reuses its connection
    config = uvicorn.Config(app, log_level="warning", access_log=False, timeout_keep_alive=75)
    uvicorn.Server(config).run(sockets=[sock])
