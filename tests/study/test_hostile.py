"""The study runner under hostile input, a held database lock and changed assets (issue 29, cases 8-10).

8: a locked SQLite database costs a request at most the store's bound, then 503 with Retry-After, and the
health says degraded; 9: answers out of order or for a stimulus never shown are refused, a ``javascript:``
redirect and a study name with path characters are refused; 10: a stimulus records the head that drew it
(re-rendered when it changes), a manifest of another version of the design is refused, and a report read
from the database hashes what it read."""

from __future__ import annotations

import html
import sqlite3
import threading
from dataclasses import replace
from pathlib import Path

import pytest
from tests.study.studies import client_for, make_study

from mien.cli import main
from mien.errors import InvalidValueError
from mien.fileio.hashing import file_sha256
from mien.study import stimuli as stimuli_module
from mien.study.design import load_design
from mien.study.export import answers_sha256
from mien.study.protocol import questions
from mien.study.runner import create_app
from mien.study.stimuli import load_manifest, make_stimuli
from mien.study.storage import StorageUnavailableError, Store, database_url

DESIGN = """
[study]
name = "hostile"
protocol = "broekens"
completion_code = "OK-1"
redirect_url = "https://example.org/back?pid={participant}"
[stimuli]
expressions = ["joy", "anger"]
heads = ["builtin"]
views = ["frontal", "lateral"]
duration_s = 0.4
fps = 5
size = 32
[design]
within = ["view"]
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    return make_study(tmp_path_factory.mktemp("hostile-study"), DESIGN)


def begin(client, participant: str) -> dict:  # type: ignore[no-untyped-def]
    session = client.post("/api/session", json={"participant": participant}).json()
    assert client.post("/api/consent", json={"participant": participant}).status_code == 200
    return session


def answer_body(session: dict, position: int, nr_shows: int = 1) -> dict:
    return {
        "participant": session["participant"],
        "stimulus": session["sequence"][position]["stimulus"],
        "position": position,
        "ratings": {q["key"]: 3 for q in session["questions"]},
        "nr_shows": nr_shows,
    }


# ------------------------------------------------------------------------------------- 8: a locked database


def test_locked_sqlite_answers_503_once_the_bound_is_spent_and_health_says_so(study: tuple, tmp_path: Path) -> None:
    db = tmp_path / "db.sqlite"
    client, store = client_for(study, db, busy_timeout_s=0.3)
    session = begin(client, "P")
    assert client.get("/api/health").json()["status"] == "ok"
    blocker = sqlite3.connect(db, timeout=0.1)
    blocker.execute("BEGIN EXCLUSIVE")  # another process holds the write lock
    try:
        reply = client.post("/api/answer", json=answer_body(session, 0))
        health = client.get("/api/health").json()
        again = client.post("/api/answer", json=answer_body(session, 0))
    finally:
        blocker.rollback()
        blocker.close()
    assert reply.status_code == 503 and reply.headers["Retry-After"] == "1"
    detail = reply.json()["detail"]
    # one attempt: SQLite's busy handler waited what was left of the bound, nothing waited it again
    assert "locked or unreachable" in detail and "1 attempt in" in detail and "bound 0.3 s" in detail
    assert health["status"] == "degraded" and health["database"] == "unavailable"
    assert health["refused"] == 1 and health["busy_timeout_s"] == 0.3 and "locked" in health["error"]
    assert again.status_code == 503  # while unavailable, each request is still bounded and answered
    assert store.count_answers() == 0
    stored = client.post("/api/answer", json=answer_body(session, 0))
    assert stored.status_code == 200 and stored.json()["stored"] == 11  # the page's retry then succeeds
    health = client.get("/api/health").json()
    assert (health["status"], health["database"], health["unavailable_since"]) == ("ok", "ok", None)
    assert health["refused"] == 2


def test_a_writer_never_queues_past_the_bound(tmp_path: Path) -> None:
    """Writers in this process queue on one lock; one stuck behind a writer that holds it is refused once the
    bound is spent (before: it waited as long as the lock was held)."""
    path = tmp_path / "queue.sqlite"
    store = Store(database_url(path, path), busy_timeout_s=0.2)
    store.register_stimuli("st", "broekens", [{"id": "s001", "expression": "joy", "conditions": {}}])
    outcome: list[object] = []

    def write() -> None:
        try:
            outcome.append(store.record_show("st", "p", "s001", 1))
        except StorageUnavailableError as error:
            outcome.append(error)

    store._write_lock.acquire()  # a writer that does not finish  # type: ignore[union-attr]
    try:
        writer = threading.Thread(target=write)
        writer.start()
        writer.join(timeout=60)  # a guard against a hang, not a timing bound
    finally:
        store._write_lock.release()  # type: ignore[union-attr]
        writer.join()
    assert len(outcome) == 1 and isinstance(outcome[0], StorageUnavailableError)
    assert "held it 0.2 s" in str(outcome[0])
    assert store.health()["database"] == "unavailable"
    assert store.record_show("st", "p", "s001", 1) == 1 and store.health()["database"] == "ok"
    store.close()


def test_busy_timeout_option(study: tuple, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    design = study[0]
    args = ["study", "export", str(design.path), "--db", str(tmp_path / "db.sqlite"), "-o", str(tmp_path / "a.csv")]
    for bad in ("0", "-1", "nan", "soon"):
        assert main([*args, "--busy-timeout", bad]) == 2
        assert "--busy-timeout" in capsys.readouterr().err
    assert main([*args, "--busy-timeout", "1.5"]) == 0
    with pytest.raises(InvalidValueError, match="busy_timeout_s"):
        Store(database_url(tmp_path / "x.sqlite", tmp_path), busy_timeout_s=0)


# ----------------------------------------------------------------------------------------- 9: hostile input


def test_answers_out_of_order_are_refused(study: tuple, tmp_path: Path) -> None:
    client, store = client_for(study, tmp_path / "db.sqlite")
    session = begin(client, "P")
    reply = client.post("/api/answer", json=answer_body(session, 2))
    assert (
        reply.status_code == 409 and "position 2" in reply.json()["detail"] and "position 0" in reply.json()["detail"]
    )
    assert store.count_answers() == 0
    assert client.post("/api/answer", json=answer_body(session, 0)).json()["stored"] == 11
    assert client.post("/api/answer", json=answer_body(session, 0)).json()["stored"] == 0  # a replay: idempotent
    assert client.post("/api/answer", json=answer_body(session, 2)).status_code == 409
    assert client.post("/api/answer", json=answer_body(session, 1)).json()["stored"] == 11
    assert list(store.answers_frame("hostile").drop_duplicates("position")["position"]) == [0, 1]


def test_answers_for_a_stimulus_never_shown_are_refused(study: tuple, tmp_path: Path) -> None:
    client, store = client_for(study, tmp_path / "db.sqlite")
    session = begin(client, "P")
    reply = client.post("/api/answer", json=answer_body(session, 0, nr_shows=0))
    assert (
        reply.status_code == 422 and "nr_shows=0" in reply.json()["detail"] and "never shown" in reply.json()["detail"]
    )
    assert store.count_answers() == 0
    stimulus = session["sequence"][0]["stimulus"]
    client.post("/api/show", json={"participant": "P", "stimulus": stimulus, "nr_shows": 2})
    assert client.post("/api/answer", json=answer_body(session, 0, nr_shows=0)).json()["stored"] == 11
    assert set(store.answers_frame("hostile")["nr_shows"]) == {2}  # the server's count of plays


def test_participant_ids_and_the_redirect(study: tuple, tmp_path: Path) -> None:
    design, manifest, folder = study
    client, _ = client_for(study, tmp_path / "db.sqlite")
    assert client.post("/api/session", json={"participant": "P1\n"}).status_code == 422  # '$' matched before \n
    session = begin(client, "a@b:c")
    for position in range(len(session["sequence"])):
        reply = client.post("/api/answer", json=answer_body(session, position)).json()
    assert reply["done"] and reply["redirect_url"] == "https://example.org/back?pid=a%40b%3Ac"
    store = Store(database_url(tmp_path / "db2.sqlite", tmp_path))
    for url in ("javascript:alert(document.cookie)", " JavaScript:alert(1)", "data:text/html,<script>", "//evil.org"):
        with pytest.raises(InvalidValueError, match="redirect_url"):
            create_app(replace(design, redirect_url=url), manifest, folder, store)
    store.close()


@pytest.mark.parametrize(
    ("line", "named"),
    [
        ('redirect_url = "javascript:alert(1)"', "redirect_url"),
        ('redirect_url = "ftp://example.org/x"', "redirect_url"),
        ('name = "../outside"', "study.name"),
        ('name = "a/b"', "study.name"),
        ('name = "..\\\\x"', "study.name"),
    ],
)
def test_design_refuses_unsafe_study_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, named: str
) -> None:
    folder = tmp_path / "study"
    folder.mkdir()
    key = line.split(" = ")[0]
    text = "\n".join(line if row.startswith(f"{key} = ") else row for row in DESIGN.splitlines())
    (folder / "design.toml").write_text(text)
    with pytest.raises(InvalidValueError, match=named):
        load_design(folder / "design.toml")
    assert main(["study", "export", str(folder / "design.toml"), "-o", str(folder / "a.csv")]) == 2
    assert named in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["design.toml", "study"]  # no database anywhere


# ----------------------------------------------------------------------------- 10: what made each stimulus


def test_a_changed_head_asset_renders_again(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.replace('views = ["frontal", "lateral"]', 'views = ["frontal"]'))
    design = load_design(path)
    first = make_stimuli(design, progress=False)
    heads = [entry["rendered_head"] for entry in first.manifest["stimuli"]]
    assert heads == [{"head": "builtin", "identity": "default", "asset_sha256": ""}] * 2
    assert (make_stimuli(design, progress=False).rendered, 0) == (0, 0)
    changed = {"head": "builtin", "identity": "default", "asset_sha256": "0" * 64}
    monkeypatch.setattr(stimuli_module, "rendered_head", lambda head, identity="": changed)
    again = make_stimuli(design, progress=False)
    assert (again.rendered, again.skipped) == (2, 0)
    assert [e["rendered_head"] for e in again.manifest["stimuli"]] == [changed] * 2


@pytest.mark.slow  # renders two clips on ICT-FaceKit and hashes its 180 MB of shapes
def test_default_head_installed_then_removed(tmp_path: Path, ict_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from mien.heads.registry import file_fingerprint

    path = tmp_path / "design.toml"
    path.write_text(DESIGN.replace('heads = ["builtin"]', 'heads = ["default"]').replace(', "lateral"', ""))
    design = load_design(path)
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(ict_dir))
    with_ict = make_stimuli(design, progress=False)
    ict = {"head": "ict", "identity": "mean", "asset_sha256": file_fingerprint(ict_dir / "FaceXModel")}
    assert [e["rendered_head"] for e in with_ict.manifest["stimuli"]] == [ict] * 2
    assert [e["conditions"]["head"] for e in with_ict.manifest["stimuli"]] == ["default"] * 2
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(tmp_path / "removed"))  # ICT uninstalled
    without = make_stimuli(design, progress=False)
    assert (without.rendered, without.skipped) == (2, 0)  # before: 0 made, 2 already done (ICT videos kept)
    assert [e["rendered_head"]["head"] for e in without.manifest["stimuli"]] == ["builtin"] * 2
    assert [e["sha256"] for e in without.manifest["stimuli"]] != [e["sha256"] for e in with_ict.manifest["stimuli"]]


def test_a_manifest_of_another_design_version_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from mien.study import runner

    served: list[object] = []
    monkeypatch.setattr(runner, "serve", lambda app, sock: served.append(app))  # never serve in a test
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.replace('views = ["frontal", "lateral"]', 'views = ["frontal"]'))
    make_stimuli(load_design(path), progress=False)
    path.write_text(path.read_text().replace('"OK-1"', '"OK-2"'))  # edited after the stimuli were made
    serve = ["study", "serve", str(path), "--db", str(tmp_path / "db.sqlite"), "--http-port", "0"]
    assert main(serve) == 2 and served == []  # before: served the stale stimuli
    err = capsys.readouterr().err
    assert f"{tmp_path / 'stimuli' / 'manifest.json'}: design_sha256" in err
    assert load_design(path).sha256 in err and f"re-run `mien study stimuli {path}`" in err
    # the report does not judge the stale stimuli either: it says why
    manifest = load_manifest(tmp_path / "stimuli")
    with Store(database_url(tmp_path / "db.sqlite", tmp_path)) as store:
        store.register_stimuli("hostile", "broekens", manifest["stimuli"])
        ids = [entry["id"] for entry in manifest["stimuli"]]
        keys = [q.key for q in questions("broekens")]
        for participant in ("P0", "P1"):
            store.ensure_participant("hostile", participant, lambda _k: (ids, keys, [0]))
            for position, stimulus in enumerate(ids):
                store.record_answer("hostile", participant, stimulus, position, dict.fromkeys(keys, 2), {}, 1)
    report = tmp_path / "report"
    analyze = ["study", "analyze", str(path), "--db", str(tmp_path / "db.sqlite"), "-o", str(report), "--quiet"]
    assert main(analyze) == 0
    capsys.readouterr()
    assert "design changed after these stimuli were made" in html.unescape((report / "report.html").read_text())
    assert main(["study", "stimuli", str(path), "--quiet"]) == 0
    assert "(0 made, 2 already done)" in capsys.readouterr().out  # nothing to render again: the text changed
    assert load_manifest(tmp_path / "stimuli")["design_sha256"] == load_design(path).sha256


def test_report_from_the_database_hashes_what_it_read(study: tuple, tmp_path: Path) -> None:
    design, _, folder = study
    db = tmp_path / "db.sqlite"
    client, store = client_for(study, db)
    for k in range(2):
        session = begin(client, f"P{k}")
        for position in range(len(session["sequence"])):
            assert client.post("/api/answer", json=answer_body(session, position)).status_code == 200
    args = [str(design.path), "--db", str(db), "--stimuli", str(folder)]
    assert main(["study", "export", *args, "-o", str(tmp_path / "answers.csv")]) == 0
    assert main(["study", "analyze", *args, "-o", str(tmp_path / "report"), "--quiet"]) == 0
    page = html.unescape((tmp_path / "report" / "report.html").read_text())
    exported = file_sha256(tmp_path / "answers.csv")
    assert exported == answers_sha256(store.answers_frame("hostile"))
    assert f'"answers_sha256": "{exported}"' in page and "(in-memory frame)" not in page
    store.close()
