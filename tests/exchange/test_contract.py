"""The exchange contract: every registered format declares suffixes; every writer's clip reads back."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.exchange import FORMATS, format_for, format_module, read_clip, reader_for, writer_for
from mien.exchange.key_reduction import default_tolerance
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip


def face_clip(n_frames: int = 40, fps: float = 30.0) -> Clip:
    t = np.arange(n_frames) / fps
    values = np.zeros((n_frames, len(FACE_CHANNELS)))
    values[:, FACE_CHANNELS.index("AU12L")] = 4.0 * np.sin(np.pi * t / t[-1]) ** 2
    values[:, FACE_CHANNELS.index("AU12R")] = 3.0 * np.sin(np.pi * t / t[-1]) ** 2
    values[:, FACE_CHANNELS.index("AU1L")] = values[:, FACE_CHANNELS.index("AU1R")] = 1.5 * t
    values[:, FACE_CHANNELS.index("head_yaw_deg")] = 12.0 * np.sin(2 * t)
    values[:, FACE_CHANNELS.index("gaze_pitch_deg")] = -5.0 * t
    return Clip(values, fps, FACE_CHANNELS)


def weight_clip(n_frames: int = 40, fps: float = 30.0) -> Clip:
    rng = np.random.default_rng(4)
    weights = np.clip(np.cumsum(rng.normal(0, 0.05, (n_frames, 52)), axis=0), 0.0, 1.0)
    pose = np.stack([10 * np.sin(np.arange(n_frames) / 9), np.linspace(-5, 5, n_frames)], axis=1)
    return Clip(np.hstack([weights, pose]), fps, (*ARKIT_NAMES, "head_yaw_deg", "head_pitch_deg"))


ROUND_TRIPS: dict[str, tuple[str, float | None, object]] = {
    # format: (clip kind, absolute tolerance, write options)
    "curves_csv": ("face", 0.0, {}),
    "clip_json": ("face", 0.0, {}),
    "clip_npz": ("face", 0.0, {}),
    "openfacs_jsonl": ("face", 0.0, {}),
    "maya_anim": ("face", None, {}),  # key reduction: within 0.5 % of each curve's value range
    "arkit_csv": ("weights", 1e-9, {}),
    "glb": ("weights", 1e-3, {}),  # float32 storage: 1e-6 for weights, 1e-3 degree for angles
    "vrm": ("weights", 1e-3, {}),  # a GLB: as glb
}
"""How each writable format round-trips. A new writer without an entry fails the test below."""


def test_every_format_declares_the_contract() -> None:
    writable = set()
    for name in FORMATS:
        module = format_module(name)
        assert module.SUFFIXES and all(s.startswith(".") for s in module.SUFFIXES)
        assert hasattr(module, "read") or hasattr(module, "write")
        if hasattr(module, "write"):
            writable.add(name)
    assert writable == set(ROUND_TRIPS)


@pytest.mark.parametrize("name", sorted(ROUND_TRIPS))
def test_round_trip_through_every_writer(tmp_path: Path, name: str) -> None:
    kind, tolerance, _ = ROUND_TRIPS[name]
    clip = face_clip() if kind == "face" else weight_clip()
    module = format_module(name)
    suffix = module.SUFFIXES[0]
    path = tmp_path / f"clip{suffix}"
    kwargs = {}
    if name in ("glb", "vrm"):
        from mien.rig.builtin_head import builtin_head

        kwargs["rig"] = builtin_head()
    writer_for(path, name)(clip, path, **kwargs)
    assert format_for(path) == name  # the suffix, and for shared suffixes the header, finds the format again
    back = read_clip(path)
    assert back.fps == pytest.approx(clip.fps, rel=1e-6)
    assert back.n_frames == clip.n_frames
    for channel in clip.channels:
        assert channel in back.channels, channel
        limit = default_tolerance(clip.channel(channel)) if tolerance is None else tolerance
        np.testing.assert_allclose(back.channel(channel), clip.channel(channel), rtol=0, atol=limit + 1e-12)
    # The same bytes go through a binary stream.
    buffer = io.BytesIO()
    module.write(clip, buffer, **kwargs)
    buffer.seek(0)
    assert module.read(buffer).n_frames == clip.n_frames


def test_non_geometry_formats_refuse_a_head(tmp_path: Path) -> None:
    from mien.rig.builtin_head import builtin_head

    for name in ROUND_TRIPS:
        if name in ("glb", "vrm"):
            continue
        with pytest.raises(InvalidValueError, match="head"):
            format_module(name).write(face_clip(3), tmp_path / "x", rig=builtin_head())


def test_registry_errors_and_sniffing(tmp_path: Path) -> None:
    with pytest.raises(UnknownNameError, match=r"\.xyz"):
        writer_for("clip.xyz")
    with pytest.raises(UnknownNameError, match="file format"):
        reader_for("clip.csv", format="excel")
    with pytest.raises(InvalidValueError, match="openface_csv"):
        writer_for("clip.csv", format="openface_csv")  # import only
    assert format_for("new.csv", "write") == "curves_csv"  # the default .csv writer
    live = tmp_path / "live.csv"
    writer_for(live, "arkit_csv")(weight_clip(5), live)
    assert format_for(live) == "arkit_csv"
    # A reader asked for before the file exists sniffs when it is called (the server uploads like this).
    reader = reader_for(tmp_path / "later.csv")
    later = tmp_path / "later.csv"
    later.write_bytes(live.read_bytes())
    assert reader(later).channels[:52] == ARKIT_NAMES
    assert reader(io.BytesIO(live.read_bytes())).channels[:52] == ARKIT_NAMES
