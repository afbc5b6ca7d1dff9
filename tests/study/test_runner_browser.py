"""A scripted participant in real headless Chromium against ``mien study serve`` running as its own process,
on SQLite and on a real PostgreSQL server: the whole session is stored with the right conditions and order;
the server is killed (SIGKILL) mid-session, an answer given while it is down is retried by the page, the
browser is closed and reopened, and the participant resumes with nothing lost or duplicated."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from mien.ports import free_port
from mien.study.design import load_design
from mien.study.stimuli import make_stimuli
from mien.study.storage import Store, database_url

pytestmark = pytest.mark.slow  # a study server, Chromium and a participant session: 7-12 s

DESIGN = """
[study]
name = "browser"
protocol = "broekens"
completion_code = "DONE-7"
[stimuli]
expressions = ["joy", "anger"]
heads = ["builtin"]
views = ["frontal", "lateral"]
duration_s = 0.6
fps = 10
size = 64
[design]
within = ["view"]
order = "counterbalanced"
"""

SHOTS = os.environ.get("MIEN_STUDY_SCREENSHOTS")
"""Folder to keep the page screenshots in (for looking at them), else the test's tmp folder."""


@pytest.fixture(scope="module")
def design_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("browser-study")
    path = folder / "design.toml"
    path.write_text(DESIGN)
    make_stimuli(load_design(path), progress=False)
    return path


class Server:
    """``mien study serve`` in a subprocess on a fixed port (restartable after a SIGKILL)."""

    def __init__(self, design: Path, db: str, port: int) -> None:
        self.command = [sys.executable, "-m", "mien.cli", "study", "serve", str(design), "--db", db,
                        "--http-port", str(port)]  # fmt: skip
        self.url = f"http://127.0.0.1:{port}"
        self.process: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        self.process = subprocess.Popen(self.command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise AssertionError(
                    f"server exited: {self.process.stderr.read().decode() if self.process.stderr else ''}"
                )
            try:
                if httpx.get(f"{self.url}/api/health", timeout=0.5).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.1)
        raise AssertionError("server did not start in 30 s")

    def kill(self) -> None:
        assert self.process is not None
        self.process.send_signal(signal.SIGKILL)
        self.process.wait(timeout=10)
        if self.process.stderr is not None:
            self.process.stderr.close()

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.kill()
        if self.process is not None and self.process.stderr is not None:
            self.process.stderr.close()


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.database)])
def db_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    if request.param == "sqlite":
        return database_url(tmp_path / "study.sqlite", tmp_path / "study.sqlite")
    url = request.getfixturevalue("postgres_url")
    with Store(url) as store, store.engine.begin() as connection:
        for table in reversed(store._meta.sorted_tables):
            connection.execute(table.delete().where(table.c.study == "browser"))
    return url


@pytest.fixture
def server(design_path: Path, db_url: str) -> Iterator[Server]:
    port = free_port()  # kept across the restart
    running = Server(design_path, db_url, port)
    running.start()
    yield running
    running.stop()


def shot(page, tmp_path: Path, name: str) -> None:  # type: ignore[no-untyped-def]
    folder = Path(SHOTS) if SHOTS else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(folder / f"{name}.png"), full_page=True)


def wait_for_trial(page, number: int) -> str:  # type: ignore[no-untyped-def]
    """Wait until video ``number`` (1-based) has loaded and played once; returns its stimulus id."""
    page.wait_for_function(
        f"document.getElementById('counter').textContent.startsWith('Video {number} of')"
        " && !document.getElementById('trial').hidden",
        timeout=15_000,
    )
    page.wait_for_function("document.getElementById('video').readyState >= 2", timeout=10_000)
    return str(page.get_attribute("#video", "data-stimulus"))


def rate(page, values: dict[str, int]) -> None:  # type: ignore[no-untyped-def]
    for key, value in values.items():
        page.check(f'input[name="{key}"][value="{value}"]')


def ratings_for(number: int) -> dict[str, int]:
    labels = ["joy", "sadness", "anger", "surprise", "disgust", "fear", "enthusiastic", "furious", "frustrated",
              "evil"]  # fmt: skip
    values = {f"label:{name}": 1 + (k + number) % 5 for k, name in enumerate(labels)}
    return {**values, "naturalness": 1 + number % 5}


def test_participant_session_with_kill_and_resume(chromium, server: Server, db_url: str, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    link = f"{server.url}/?participant=prolific-123"
    page = chromium.new_page()
    page.goto(link)
    page.wait_for_selector("#consent:not([hidden])")
    shot(page, tmp_path, "1-consent")
    assert page.is_disabled("#consent-button")
    page.check("#consent-check")
    page.click("#consent-button")
    page.wait_for_selector("#instructions:not([hidden])")
    shot(page, tmp_path, "2-instructions")
    page.click("#start-button")
    order = [wait_for_trial(page, 1)]
    on_screen = page.eval_on_selector_all("#questions fieldset", "sets => sets.map(s => s.dataset.key)")
    page.wait_for_function("document.getElementById('shows').textContent === ''")
    page.click("#replay-button")  # replay: nrShows 2
    page.wait_for_selector("text=(played 2 times)")
    rate(page, ratings_for(1))
    shot(page, tmp_path, "3-trial")
    page.evaluate("() => { const next = document.getElementById('next-button'); next.click(); next.click(); }")
    order.append(wait_for_trial(page, 2))
    rate(page, ratings_for(2))
    page.click("#next-button")
    order.append(wait_for_trial(page, 3))

    with Store(db_url) as store:
        assert store.count_answers("browser") == 22  # both answers committed before the kill
    server.kill()  # mid-session, with video 3 on screen
    rate(page, ratings_for(3))
    page.click("#next-button")  # the server is down: the page retries
    time.sleep(0.5)
    server.start()
    order.append(wait_for_trial(page, 4))
    page.close()  # the participant closes the browser ...

    page = chromium.new_page()  # ... and reopens the link
    page.goto(link)
    page.wait_for_selector("#instructions:not([hidden])")
    assert page.text_content("#instructions-title") == "Welcome back"
    assert "video 4 of 4" in page.text_content("#start-button")
    shot(page, tmp_path, "4-welcome-back")
    page.click("#start-button")
    assert wait_for_trial(page, 4) == order[3]
    assert page.eval_on_selector_all("#questions fieldset", "sets => sets.map(s => s.dataset.key)") == on_screen
    rate(page, ratings_for(4))
    page.click("#next-button")
    page.wait_for_selector("#done:not([hidden])")
    assert page.text_content("#code") == "DONE-7"
    shot(page, tmp_path, "5-done")
    page.close()

    with Store(db_url) as store:
        frame = store.answers_frame("browser")
        participant = store.participant("browser", "prolific-123")
    assert participant is not None and participant.completed_at is not None
    assert len(frame) == 44 and not frame.duplicated(["stimulus", "question"]).any()
    assert list(frame.drop_duplicates("position")["stimulus"]) == order == list(participant.sequence)
    views = frame.drop_duplicates("position")["view"].tolist()
    assert views[0] == views[1] and views[2] == views[3] and views[0] != views[2]  # blocks of the within factor
    for number, stimulus in enumerate(order, 1):
        rows = frame[frame["stimulus"] == stimulus].set_index("question")
        assert rows["rating"].to_dict() == ratings_for(number)
        assert (rows["position"] == number - 1).all()
    labels = frame[frame["position"] == 0].dropna(subset=["label_position"]).sort_values("label_position")
    assert labels["question"].tolist() == on_screen[:10]
    nr_shows = frame.drop_duplicates("position")["nr_shows"].tolist()
    assert nr_shows[0] == 2 and all(n >= 1 for n in nr_shows)
