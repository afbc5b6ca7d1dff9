"""``mien assets fetch``: download from a real local HTTP server, hash check, atomic install, clean failures."""

from __future__ import annotations

import hashlib
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from tests.loopback import serve_folder

from mien.cli import main
from mien.ports import free_port


@pytest.fixture(scope="module")
def ict_zip(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """A zip laid out like GitHub's archive of ICT-FaceKit (one top folder), holding only the files mien needs."""
    from mien.rig.ict_facekit import _REQUIRED_FILES

    folder = tmp_path_factory.mktemp("served")
    archive = folder / "ICT-FaceKit-master.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_STORED) as package:  # stored: fast to build and serve
        for name in _REQUIRED_FILES:
            package.write(ict_dir / "FaceXModel" / name, f"ICT-FaceKit-master/FaceXModel/{name}")
        package.write(ict_dir / "LICENSE", "ICT-FaceKit-master/LICENSE")
    (folder / "not-a-zip.zip").write_bytes(b"this is not a zip archive" * 100)
    return archive, hashlib.sha256(archive.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def server(ict_zip: tuple[Path, str]) -> Iterator[str]:
    """A real HTTP server on 127.0.0.1 (ephemeral port) serving the zip's folder; yields its base URL."""
    with serve_folder(ict_zip[0].parent) as url:
        yield url


@pytest.fixture
def data_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty user data folder, with no variable or config pointing at a head."""
    monkeypatch.setenv("MIEN_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "no-config.toml"))
    monkeypatch.delenv("MIEN_ICT_FACEKIT", raising=False)
    return tmp_path / "data"


def _leftovers(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")) if folder.exists() else []


def test_fetch_installs_where_mien_looks_and_the_head_loads(
    server: str, ict_zip: tuple[Path, str], data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mien.paths import asset_path
    from mien.rig.ict_facekit import ict_missing_files, load_ict_facekit

    assert asset_path("ict_facekit") is None  # nothing configured before the fetch
    url = f"{server}/{ict_zip[0].name}"
    assert main(["assets", "fetch", "ict-facekit", "--url", url, "--sha256", ict_zip[1].upper(), "--quiet"]) == 0
    installed = data_dir / "ict-facekit"
    assert str(installed) in capsys.readouterr().out
    assert asset_path("ict_facekit") == installed and ict_missing_files() == []
    assert _leftovers(data_dir) == sorted(
        ["ict-facekit", "ict-facekit/FaceXModel", "ict-facekit/LICENSE"]
        + [f"ict-facekit/FaceXModel/{p.name}" for p in (installed / "FaceXModel").iterdir()]
    )  # no partial folder, no archive left
    rig = load_ict_facekit(cache=False)  # from the installed path, found by mien.paths alone
    assert rig.n_vertices == 26_719 and np.isfinite(rig.neutral).all() and len(rig.targets) > 52
    assert main(["assets", "--json"]) == 0
    assert '"source": "installed"' in capsys.readouterr().out
    # A second fetch refuses to overwrite; --force replaces atomically.
    assert main(["assets", "fetch", "ict-facekit", "--url", url, "--sha256", ict_zip[1], "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err
    argv = ["assets", "fetch", "ict-facekit", "--url", url, "--sha256", ict_zip[1], "--quiet", "--force"]
    assert main(argv) == 0 and ict_missing_files() == []
    assert [p.name for p in data_dir.iterdir()] == ["ict-facekit"]


def _refused_port() -> int:
    return free_port()  # closed again: connecting is refused


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("wrong hash", "does not match, nothing was installed"),
        ("404", "HTTP 404"),
        ("refused", "Connection refused"),
        ("not a zip", "a zip archive"),
        ("no hash known", "run again with --sha256"),
        ("bad hash text", "64 hexadecimal digits"),
    ],
)
def test_failed_fetch_is_exit_2_and_leaves_nothing(
    case: str,
    message: str,
    server: str,
    ict_zip: tuple[Path, str],
    data_dir: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    url, sha = f"{server}/{ict_zip[0].name}", ict_zip[1]
    extra = {
        "wrong hash": ["--url", url, "--sha256", "0" * 64],
        "404": ["--url", f"{server}/missing.zip", "--sha256", sha],
        "refused": ["--url", f"http://127.0.0.1:{_refused_port()}/x.zip", "--sha256", sha],
        "not a zip": [
            "--url",
            f"{server}/not-a-zip.zip",
            "--sha256",
            hashlib.sha256(b"this is not a zip archive" * 100).hexdigest(),
        ],
        "no hash known": ["--url", url],
        "bad hash text": ["--url", url, "--sha256", "abc"],
    }[case]
    assert main(["assets", "fetch", "ict-facekit", *extra, "--quiet", "--timeout", "5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mien assets: error: ") and message in err and "Traceback" not in err
    assert err.count("\n") == 1
    assert not data_dir.exists()  # not even the data folder: nothing is left behind
    if case == "no hash known":
        assert sha in err  # the measured hash, to check and pass back


def test_unknown_asset_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["assets", "fetch", "ict-facekti"]) == 2
    assert "unknown fetchable asset 'ict-facekti'; known: ict-facekit" in capsys.readouterr().err
