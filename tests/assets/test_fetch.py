"""``mien assets fetch``: the files mien reads, one by one from a real HTTP server on 127.0.0.1 that serves the
shared ICT-FaceKit copy as if it were the pinned commit; hashes, resume after a cut, clean failures."""

from __future__ import annotations

import errno
import hashlib
import http.server
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from tests.loopback import serve_folder

from mien.assets.fetch import SOURCES, file_hashes, files_to_fetch, staging_folder
from mien.cli import main
from mien.ports import free_port

ICT = SOURCES["ict-facekit"]
THIRD = "FaceXModel/vertex_indices.json"
"""The third file fetched (after LICENSE and the neutral mesh): where most faults are put."""


class FaultyServer(http.server.SimpleHTTPRequestHandler):
    """Serves files with HTTP Range support and the faults of :attr:`faults` (URL path -> fault)."""

    faults: dict[str, str] = {}  # noqa: RUF012 (one table shared by the handler instances, reset per test)
    """``"404"``, ``"differ"`` (one byte flipped), ``"cut"`` (half the body, then the connection closes),
    ``"cut once"`` (a cut on the first request only), ``"stall"`` (half the body, then a 1 s silence),
    ``"whole"`` (the whole file, whatever the Range header asks)."""
    requests: list[tuple[str, str | None]] = []  # noqa: RUF012
    """(URL path, Range header) of every request, in order."""

    def log_message(self, format: str, *args: object) -> None:
        pass

    def do_GET(self) -> None:
        path = self.path.split("?")[0]
        self.requests.append((path, self.headers.get("Range")))
        fault = self.faults.get(path)
        if fault == "cut once":
            del self.faults[path]
        local = Path(self.translate_path(path))
        if fault == "404" or not local.is_file():
            self.send_error(404)
            return
        data = local.read_bytes()
        if fault == "differ":
            data = bytes([data[0] ^ 1]) + data[1:]
        ranged = None if fault == "whole" else re.fullmatch(r"bytes=(\d+)-", self.headers.get("Range") or "")
        start = int(ranged[1]) if ranged else 0
        if start >= len(data) > 0:
            self.send_error(416)
            return
        self.send_response(206 if ranged else 200)
        if ranged:
            self.send_header("Content-Range", f"bytes {start}-{len(data) - 1}/{len(data)}")
        self.send_header("Content-Length", str(len(data) - start))
        self.end_headers()
        body = data[start:]
        if fault in ("cut", "cut once", "stall"):
            self.wfile.write(body[: len(body) // 2])
            self.wfile.flush()
            if fault == "stall":  # then nothing, longer than the client waits
                time.sleep(1.0)
            self.close_connection = True
            return
        self.wfile.write(body)


@pytest.fixture(scope="module")
def server(ict_dir: Path) -> Iterator[str]:
    """The shared ICT-FaceKit folder served on 127.0.0.1 (ephemeral port) at the paths of the commit."""
    with serve_folder(ict_dir, FaultyServer) as url:
        yield url


@pytest.fixture(autouse=True)
def no_faults() -> Iterator[None]:
    FaultyServer.faults.clear()
    FaultyServer.requests.clear()
    yield
    FaultyServer.faults.clear()


@pytest.fixture
def data_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty user data folder, with no variable or config pointing at a head."""
    monkeypatch.setenv("MIEN_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "no-config.toml"))
    monkeypatch.delenv("MIEN_ICT_FACEKIT", raising=False)
    return tmp_path / "data"


def _tree(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()) if folder.exists() else []


def _fetch(server: str, *extra: str) -> list[str]:
    return ["assets", "fetch", "ict-facekit", "--url", server, "--quiet", "--timeout", "10", *extra]


def test_the_source_pins_the_commit_and_ships_its_hash_list(ict_dir: Path) -> None:
    assert ICT.commit == "da5f95a607f5e6b37755b38d3385d7f2853732e5"
    assert ICT.base_url == f"https://raw.githubusercontent.com/ICT-VGL/ICT-FaceKit/{ICT.commit}"
    shipped = Path(__file__).parents[2] / "src/mien/assets/data" / ICT.hashes
    assert shipped.read_bytes() == (ict_dir.parent / "ict-facekit-da5f95a.sha256").read_bytes()
    hashes = file_hashes(ICT)
    files = files_to_fetch(ICT)
    assert len(hashes) == 162 and files[:3] == ("LICENSE", "FaceXModel/generic_neutral_mesh.obj", THIRD)
    assert len(files) == len(set(files)) == 76 and set(files) <= set(hashes)  # the loader's 75 + the licence
    assert {f"FaceXModel/identity{i:03d}.obj" for i in range(16, 100)}.isdisjoint(files)  # mien reads 16 of 100
    assert ICT.download_bytes == sum((ict_dir / path).stat().st_size for path in files)
    for path in files:  # the served copy is the commit's
        assert hashlib.sha256((ict_dir / path).read_bytes()).hexdigest() == hashes[path], path
    assert ICT.licence == "MIT" and (ict_dir / "LICENSE").read_text().startswith("MIT License")


def test_a_cut_fetch_resumes_with_a_range_request_and_installs_where_mien_looks(
    server: str, ict_dir: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mien.paths import asset_path
    from mien.rig.ict_facekit import ict_missing_files

    assert asset_path("ict_facekit") is None  # nothing configured before the fetch
    target, staging = data_dir / "ict-facekit", staging_folder(data_dir / "ict-facekit")
    FaultyServer.faults[f"/{THIRD}"] = "cut once"
    assert main(_fetch(server)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mien assets: error: {THIRD}: the connection closed after ") and err.count("\n") == 1
    assert f"2 of 76 files (3 MiB) are kept in {staging}: run the same command again to resume" in err
    assert not target.exists()  # never half-installed
    assert _tree(staging) == ["FaceXModel/generic_neutral_mesh.obj", "FaceXModel/vertex_indices.json.part", "LICENSE"]
    half = (staging / (THIRD + ".part")).stat().st_size
    assert half == (ict_dir / THIRD).stat().st_size // 2

    FaultyServer.requests.clear()
    assert main(_fetch(server)) == 0
    assert f"installed ict-facekit (MIT licence, {ICT.repository} at da5f95a) in {target}" in capsys.readouterr().out
    requested = dict(FaultyServer.requests)
    assert len(FaultyServer.requests) == len(requested) == 74  # the two verified files are not fetched again
    assert requested[f"/{THIRD}"] == f"bytes={half}-" and set(requested.values()) == {None, f"bytes={half}-"}
    assert not staging.exists() and sorted(_tree(data_dir)) == sorted(f"ict-facekit/{p}" for p in files_to_fetch(ICT))
    hashes = file_hashes(ICT)
    assert all(hashlib.sha256((target / p).read_bytes()).hexdigest() == hashes[p] for p in files_to_fetch(ICT))
    assert asset_path("ict_facekit") == target and ict_missing_files() == []
    assert main(["assets", "--json"]) == 0
    assert '"source": "installed"' in capsys.readouterr().out
    # A second fetch refuses to overwrite, before any download.
    FaultyServer.requests.clear()
    assert main(_fetch(server)) == 2
    assert "--force" in capsys.readouterr().err and FaultyServer.requests == []


@pytest.mark.parametrize(
    ("fault", "words"),
    [
        (
            "differ",
            [f"{THIRD} from ", "has SHA-256 ", f"not the {file_hashes(ICT)[THIRD]} recorded for commit da5f95a"],
        ),
        ("404", [f"{THIRD}: the server answered HTTP 404", "check --url", "same paths"]),
    ],
)
def test_a_file_that_differs_or_is_missing_installs_nothing_and_leaves_nothing(
    fault: str, words: list[str], server: str, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    FaultyServer.faults[f"/{THIRD}"] = fault
    assert main(_fetch(server)) == 2
    err = capsys.readouterr().err
    assert err.startswith("mien assets: error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert all(word in err for word in words) and err.endswith("; nothing was installed\n"), err
    assert not data_dir.exists()  # not even the data folder: nothing is left behind
    assert [path for path, _ in FaultyServer.requests] == [
        "/LICENSE",
        "/FaceXModel/generic_neutral_mesh.obj",
        f"/{THIRD}",
    ]


def test_force_replaces_an_install_only_when_the_new_one_is_complete(
    server: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    old = tmp_path / "ict"
    (old / "FaceXModel").mkdir(parents=True)
    (old / "FaceXModel" / "mine.obj").write_text("v 0 0 0\n")
    FaultyServer.faults[f"/{THIRD}"] = "differ"
    assert main(_fetch(server, "-o", str(old), "--force")) == 2
    assert "nothing was installed" in capsys.readouterr().err
    assert _tree(tmp_path) == ["ict/FaceXModel/mine.obj"]
    FaultyServer.faults.clear()
    assert main(_fetch(server, "-o", str(old), "--force")) == 0  # the old install goes once the new one is whole
    assert _tree(tmp_path) == sorted(f"ict/{path}" for path in files_to_fetch(ICT))


@pytest.mark.parametrize(
    ("fault", "timeout", "words"),
    [
        ("cut", "10", "the connection closed after 1,277,799 of 2,555,599 bytes"),
        ("stall", "0.3", "generic_neutral_mesh.obj sent nothing for 0.3 s (on a slow network raise --timeout)"),
    ],
)
def test_a_cut_or_stalled_connection_keeps_only_verified_files(
    fault: str, timeout: str, words: str, server: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    FaultyServer.faults["/FaceXModel/generic_neutral_mesh.obj"] = fault
    target = tmp_path / "ict"
    assert main([*_fetch(server, "-o", str(target)), "--timeout", timeout]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mien assets: error: FaceXModel/generic_neutral_mesh.obj: ") and err.count("\n") == 1
    assert words in err and "1 of 76 files (1 MiB) are kept" in err and "run the same command again to resume" in err
    assert _tree(tmp_path) == [".ict.partial/FaceXModel/generic_neutral_mesh.obj.part", ".ict.partial/LICENSE"]


def test_a_server_that_ignores_range_restarts_the_partial_file(
    server: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "ict"
    fourth = files_to_fetch(ICT)[3]
    FaultyServer.faults.update({f"/{THIRD}": "cut", f"/{fourth}": "404"})
    assert main(_fetch(server, "-o", str(target))) == 2
    assert "kept" in capsys.readouterr().err
    FaultyServer.faults[f"/{THIRD}"] = "whole"
    FaultyServer.requests.clear()
    assert main(_fetch(server, "-o", str(target))) == 2  # stops at the fourth file, after the third is verified
    assert "HTTP 404" in capsys.readouterr().err
    half = "bytes=82026-"
    assert FaultyServer.requests == [(f"/{THIRD}", half), (f"/{fourth}", None)]
    assert not target.exists() and not staging_folder(target).exists()  # a 404 leaves nothing


def test_ctrl_c_keeps_the_verified_files_and_says_so(
    server: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    real_rename = pathlib.Path.rename

    def interrupted_rename(self: Path, target: Any) -> Any:
        if self.name == "vertex_indices.json.part":  # Ctrl-C as the third file is done
            raise KeyboardInterrupt
        return real_rename(self, target)

    monkeypatch.setattr(pathlib.Path, "rename", interrupted_rename)
    target = tmp_path / "ict"
    assert main(_fetch(server, "-o", str(target))) == 130
    staging = staging_folder(target)
    assert capsys.readouterr().err == (
        f"the files verified so far are kept in {staging}: run the same command again to resume\ninterrupted\n"
    )
    assert _tree(staging) == ["FaceXModel/generic_neutral_mesh.obj", "FaceXModel/vertex_indices.json.part", "LICENSE"]


def test_an_unreachable_server_leaves_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    port = free_port()  # closed again: connecting is refused
    assert main(_fetch(f"http://127.0.0.1:{port}/mirror", "-o", str(tmp_path / "new" / "ict"))) == 2
    err = capsys.readouterr().err
    assert f"could not reach http://127.0.0.1:{port}/mirror/LICENSE (Connection refused)" in err
    assert "nothing was installed" in err and list(tmp_path.iterdir()) == []


class _FullDisk:
    """A file whose writes fail with ENOSPC once ``room`` bytes are written (a disk that fills up)."""

    def __init__(self, handle: Any, room: int) -> None:
        self.handle, self.room = handle, room

    def write(self, data: bytes) -> int:
        if not self.room:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written = int(self.handle.write(data[: self.room]))  # a short write first, as a filling disk does
        self.room -= written
        return written

    def __enter__(self) -> _FullDisk:
        return self

    def __exit__(self, *exc: object) -> None:
        self.handle.close()


def test_a_full_disk_is_a_clear_error_and_leaves_nothing(
    server: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Simulated: the third file's writes fail with ENOSPC after 64 KiB."""
    real_open = pathlib.Path.open

    def open_(self: Path, mode: str = "r", *args: Any, **kwargs: Any) -> Any:
        handle = real_open(self, mode, *args, **kwargs)
        return _FullDisk(handle, 1 << 16) if self.name == "vertex_indices.json.part" else handle

    monkeypatch.setattr(pathlib.Path, "open", open_)
    target = tmp_path / "ict"
    assert main(_fetch(server, "-o", str(target))) == 2
    err = capsys.readouterr().err
    part = staging_folder(target) / (THIRD + ".part")
    assert err == f"mien assets: error: could not write {part} (No space left on device); nothing was installed\n"
    assert list(tmp_path.iterdir()) == []


def test_a_full_tmpfs_is_a_clear_error_and_leaves_nothing(server: str, tmp_path: Path) -> None:
    """Real: a 2 MiB tmpfs in a private mount namespace (``unshare``); skipped where namespaces are not allowed."""
    mount = tmp_path / "tiny"
    mount.mkdir()
    probe = ["unshare", "-rm", "sh", "-c", f"mount -t tmpfs -o size=2m tmpfs {mount}"]
    if shutil.which("unshare") is None or subprocess.run(probe, capture_output=True).returncode != 0:
        pytest.skip("no unshare or no user mount namespaces here: the simulated full disk test covers it")
    script = (
        f"mount -t tmpfs -o size=2m tmpfs {mount} && "
        f"{sys.executable} -m mien.cli {' '.join(_fetch(server, '-o', str(mount / 'ict')))}; "
        f"echo exit=$?; ls -A {mount}"
    )
    done = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True, timeout=120)
    assert done.stdout == "exit=2\n"  # and `ls -A` of the tmpfs printed nothing: nothing left behind
    assert done.stderr == (
        f"mien assets: error: could not write {mount}/.ict.partial/FaceXModel/generic_neutral_mesh.obj.part "
        "(No space left on device); nothing was installed\n"
    )


def test_unknown_asset_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["assets", "fetch", "ict-facekti"]) == 2
    assert "unknown fetchable asset 'ict-facekti'; known: ict-facekit" in capsys.readouterr().err
