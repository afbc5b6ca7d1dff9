"""The runner's JSON API in process (FastAPI TestClient): a whole session, resume, double submits, replays,
bad requests (4xx naming the value) and a locked database (503, nothing stored)."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from tests.study.studies import client_for, make_study

from mien.ports import free_port
from mien.study.design import load_design
from mien.study.stimuli import make_stimuli

DESIGN = """
[study]
name = "api"
protocol = "broekens"
completion_code = "XYZ-42"
redirect_url = "https://example.org/back?pid={participant}"
[stimuli]
expressions = ["joy", "anger"]
heads = ["builtin"]
views = ["frontal", "lateral"]
duration_s = 0.6
fps = 10
size = 48
[design]
within = ["view"]
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    return make_study(tmp_path_factory.mktemp("api-study"), DESIGN)


def answers_for(session: dict, value: int = 3) -> dict[str, int]:
    return {q["key"]: value for q in session["questions"]}


def test_session_resume_and_idempotence(study: tuple, tmp_path: Path) -> None:
    client, store = client_for(study, tmp_path / "db.sqlite")
    s = client.post("/api/session", json={"participant": "P-1"}).json()
    assert (s["participant"], s["consent_given"], s["next_position"], s["done"]) == ("P-1", False, 0, False)
    assert len(s["sequence"]) == 4 and len(s["questions"]) == 11 and s["questions"][-1]["key"] == "naturalness"
    assert client.get(s["sequence"][0]["url"]).content[4:8] == b"ftyp"  # the MP4 itself
    assert client.post("/api/consent", json={"participant": "P-1"}).status_code == 200
    first = s["sequence"][0]
    for n in (1, 2, 2):
        shown = client.post("/api/show", json={"participant": "P-1", "stimulus": first["stimulus"], "nr_shows": n})
    assert shown.json() == {"nr_shows": 2}
    body = {
        "participant": "P-1",
        "stimulus": first["stimulus"],
        "position": 0,
        "ratings": answers_for(s),
        "nr_shows": 2,
    }
    reply = client.post("/api/answer", json=body).json()
    assert (reply["stored"], reply["next_position"], reply["done"]) == (11, 1, False)
    assert client.post("/api/answer", json=body).json()["stored"] == 0  # double submit
    again = client.post("/api/session", json={"participant": "P-1"}).json()  # reopened page
    assert (again["consent_given"], again["next_position"], again["answered"]) == (True, 1, 1)
    assert again["sequence"] == s["sequence"] and again["questions"] == s["questions"]
    assert again["nr_shows"] == {first["stimulus"]: 2}
    for item in s["sequence"][1:]:
        reply = client.post(
            "/api/answer",
            json={"participant": "P-1", "stimulus": item["stimulus"], "position": item["position"],
                  "ratings": answers_for(s, 4), "nr_shows": 1},
        ).json()  # fmt: skip
    assert reply["done"] and reply["completion_code"] == "XYZ-42"
    assert reply["redirect_url"] == "https://example.org/back?pid=P-1"
    frame = store.answers_frame("api")
    assert len(frame) == 44 and frame.groupby("stimulus").size().eq(11).all()
    assert list(frame.drop_duplicates("position")["stimulus"]) == [i["stimulus"] for i in s["sequence"]]
    labels = frame[frame["stimulus"] == first["stimulus"]].dropna(subset=["label_position"])
    assert list(labels["question"]) == [q["key"] for q in s["questions"][:10]]  # on-screen order stored
    assert store.participant("api", "P-1").completed_at is not None
    generated = client.post("/api/session", json={}).json()["participant"]
    assert len(generated) == 12 and generated != "P-1"


@pytest.mark.parametrize(
    ("path", "body", "named"),
    [
        ("/api/session", {"participant": "a b"}, "'a b'"),
        ("/api/consent", {"participant": "ghost"}, "'ghost'"),
        ("/api/show", {"participant": "P", "stimulus": "s999", "nr_shows": 1}, "'s999'"),
        ("/api/answer", {"participant": "P", "stimulus": "s001", "position": 99, "ratings": {}, "nr_shows": 1}, "99"),
        (
            "/api/answer",
            {"participant": "P", "stimulus": "FIRST", "position": 0, "ratings": {"naturalness": 9}, "nr_shows": 1},
            "missing",
        ),
    ],
)
def test_bad_requests_name_the_value(study: tuple, tmp_path: Path, path: str, body: dict, named: str) -> None:
    client, _ = client_for(study, tmp_path / "db.sqlite")
    s = client.post("/api/session", json={"participant": "P"}).json()
    client.post("/api/consent", json={"participant": "P"})
    if body.get("stimulus") == "FIRST":
        body = {**body, "stimulus": s["sequence"][0]["stimulus"]}
    reply = client.post(path, json=body)
    assert 400 <= reply.status_code < 500 and named in str(reply.json()["detail"])
    assert client.get("/api/health").status_code == 200  # the server lives on


def test_out_of_range_rating(study: tuple, tmp_path: Path) -> None:
    client, store = client_for(study, tmp_path / "db.sqlite")
    s = client.post("/api/session", json={"participant": "P"}).json()
    item = s["sequence"][0]
    body = {"participant": "P", "stimulus": item["stimulus"], "position": 0, "ratings": answers_for(s), "nr_shows": 1}
    reply = client.post("/api/answer", json=body)
    assert reply.status_code == 409 and "consent" in reply.json()["detail"]
    client.post("/api/consent", json={"participant": "P"})
    ratings = {**answers_for(s), "naturalness": 6}
    body = {"participant": "P", "stimulus": item["stimulus"], "position": 0, "ratings": ratings, "nr_shows": 1}
    reply = client.post("/api/answer", json=body)
    assert reply.status_code == 422 and "naturalness=6" in reply.json()["detail"]
    assert store.count_answers() == 0


def test_locked_database_gives_503(study: tuple, tmp_path: Path) -> None:
    db = tmp_path / "db.sqlite"
    client, store = client_for(study, db, retry_s=0.01, busy_timeout_s=0.05)
    s = client.post("/api/session", json={"participant": "P"}).json()
    client.post("/api/consent", json={"participant": "P"})
    item = s["sequence"][0]
    body = {"participant": "P", "stimulus": item["stimulus"], "position": 0, "ratings": answers_for(s), "nr_shows": 1}
    blocker = sqlite3.connect(db, timeout=0.1)
    blocker.execute("BEGIN EXCLUSIVE")
    try:
        reply = client.post("/api/answer", json=body)
    finally:
        blocker.rollback()
        blocker.close()
    assert reply.status_code == 503 and "locked or unreachable" in reply.json()["detail"]
    assert store.count_answers() == 0
    assert client.post("/api/answer", json=body).json()["stored"] == 11  # the page's retry then succeeds


def test_export_and_analyze_commands(study: tuple, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from mien.cli import main
    from mien.study.export import read_answers_csv

    design, _, folder = study
    db = tmp_path / "db.sqlite"
    client, store = client_for(study, db)
    for k in range(3):
        s = client.post("/api/session", json={"participant": f"P{k}"}).json()
        client.post("/api/consent", json={"participant": f"P{k}"})
        for item in s["sequence"]:
            ratings = {q["key"]: 1 + (i + k + item["position"]) % 5 for i, q in enumerate(s["questions"])}
            body = {"participant": f"P{k}", "stimulus": item["stimulus"], "position": item["position"],
                    "ratings": ratings, "nr_shows": 1}  # fmt: skip
            assert client.post("/api/answer", json=body).status_code == 200
    out = tmp_path / "answers.csv"
    args = [str(design.path), "--db", str(db), "--stimuli", str(folder)]
    assert main(["study", "export", *args, "-o", str(out)]) == 0
    assert "wrote 132 answers" in capsys.readouterr().out
    frame = read_answers_csv(out)
    assert frame.equals(store.answers_frame("api"))
    report = tmp_path / "report"
    assert main(["study", "analyze", *args, "--answers", str(out), "-o", str(report)]) == 0
    assert (report / "report.html").is_file()
    assert main(["study", "analyze", str(design.path), "--db", str(tmp_path / "empty.sqlite")]) == 2
    assert "at least one stored answer" in capsys.readouterr().err


def test_serve_refuses_clearly(study: tuple, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import socket

    from mien.cli import main

    design, _, folder = study
    closed_port = free_port()
    args = ["study", "serve", str(design.path), "--stimuli", str(folder), "--http-port", "0"]
    assert main([*args, "--db", f"postgresql://postgres@127.0.0.1:{closed_port}/x"]) == 2
    assert "locked or unreachable" in capsys.readouterr().err
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert main([*args[:-1], str(port)]) == 2
        assert f"--http-port={port} is invalid" in capsys.readouterr().err
    assert main([*args[:3], "--stimuli", str(tmp_path)]) == 2
    assert "run `mien study stimuli" in capsys.readouterr().err


MASCARO = """
[study]
name = "laughs"
protocol = "mascaro"
[stimuli]
laughter_types = ["sly_smile", "false_laughter"]
duration_s = 0.5
fps = 6
size = 32
[stimuli.descriptions]
sly_smile = "A sly, knowing smile"
"""


def test_mascaro_protocol(tmp_path: Path) -> None:
    path = tmp_path / "laughs.toml"
    path.write_text(MASCARO)
    design = load_design(path)
    result = make_stimuli(design, progress=False)
    client, store = client_for((design, result.manifest, result.manifest_path.parent), tmp_path / "db.sqlite")
    s = client.post("/api/session", json={"participant": "M1"}).json()
    client.post("/api/consent", json={"participant": "M1"})
    assert [q["key"] for q in s["questions"]] == ["feels_right", "represents_description"]
    assert {(q["low"], q["high"]) for q in s["questions"]} == {(0, 5)}
    assert {i["description"] for i in s["sequence"]} == {"A sly, knowing smile", "False laughter"}
    for item in s["sequence"]:
        body = {"participant": "M1", "stimulus": item["stimulus"], "position": item["position"],
                "ratings": {"feels_right": 0, "represents_description": 5}, "nr_shows": 1}  # fmt: skip
        assert client.post("/api/answer", json=body).json()["stored"] == 2
    frame = store.answers_frame("laughs")
    assert list(frame.columns[7:9]) == ["laughter_type", "description"]
    assert frame["label_position"].isna().all() and set(frame["rating"]) == {0, 5}
