"""Golden files for each writer, the real OpenFace CSV, Live Link by column name, and bad input per reader."""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError
from mien.exchange import arkit_csv, clip_json, curves_csv, glb, openface_csv, openfacs_jsonl, read_clip
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import au_channels
from mien.facs.clip import Clip
from mien.rig.model import MorphTarget, Rig

DATA = Path(__file__).parent / "data"
OPENFACE = "formats/OpenFace_Test.csv"


def tiny_face_clip() -> Clip:
    values = np.array([[0.0, 0.0, 0.0], [2.5, 1.0, 10.0], [5.0, 0.5, -4.25]])
    return Clip(values, 25.0, ("AU12L", "AU12R", "head_yaw_deg"))


def tiny_weight_clip() -> Clip:
    values = np.zeros((3, 54))
    values[:, ARKIT_NAMES.index("jawOpen")] = [0.0, 0.5, 1.0]
    values[:, ARKIT_NAMES.index("eyeBlinkLeft")] = [1.0, 0.25, 0.0]
    values[:, 52] = [0.0, 5.0, 10.0]
    return Clip(values, 30.0, (*ARKIT_NAMES, "head_yaw_deg", "head_pitch_deg"))


def tiny_rig() -> Rig:
    neutral = np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0]])
    target = MorphTarget("jawOpen", np.array([0]), np.array([[0.0, -0.05, 0.0]]))
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    return Rig("tiny", neutral, faces, (target,), np.zeros(68, np.int32))


GOLDEN = {
    "tiny_curves.csv": lambda target: curves_csv.write(tiny_face_clip(), target),
    "tiny_clip.json": lambda target: clip_json.write(tiny_face_clip(), target),
    "tiny_openfacs.jsonl": lambda target: openfacs_jsonl.write(tiny_face_clip(), target),
    "tiny_livelink.csv": lambda target: arkit_csv.write(tiny_weight_clip(), target),
    "tiny.glb.txt": lambda target: glb.write(
        Clip(np.array([[0.0], [1.0], [0.5]]), 10.0, ("jawOpen",)), target, tiny_rig()
    ),
}


def glb_as_text(data: bytes) -> bytes:
    """A byte-exact text form of a .glb: its header, the JSON chunk as written, the BIN chunk in hex.

    The golden .glb is kept as this text so the repository holds no binary; every byte still takes part.
    """
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    lines = [f"header {magic.decode()} version {version} length {length}"]
    offset = 12
    while offset < len(data):
        chunk_length, chunk_type = struct.unpack_from("<I4s", data, offset)
        body = data[offset + 8 : offset + 8 + chunk_length]
        name = chunk_type.rstrip(bytes(1)).decode()
        lines.append(f"chunk {name} {chunk_length} bytes")
        if name == "JSON":
            lines.append(body.decode("utf-8"))  # one line, its space padding kept
        else:
            lines += [body[i : i + 32].hex() for i in range(0, len(body), 32)]
        offset += 8 + chunk_length
    return ("\n".join(lines) + "\n").encode()


@pytest.mark.parametrize("name", sorted(GOLDEN))
def test_writers_match_golden_files(name: str) -> None:
    buffer = io.BytesIO()
    GOLDEN[name](buffer)
    written = glb_as_text(buffer.getvalue()) if name.endswith(".glb.txt") else buffer.getvalue()
    assert written == (DATA / name).read_bytes()


def test_golden_live_link_header_and_timecode() -> None:
    lines = (DATA / "tiny_livelink.csv").read_text().splitlines()
    assert lines[0].startswith("Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,")
    assert lines[0].endswith(
        ",TongueOut,HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll"
    )
    assert [line.split(",")[:2] for line in lines[1:]] == [
        ["00:00:00:00.000", "61"],
        ["00:00:00:02.000", "61"],
        ["00:00:00:04.000", "61"],
    ]


def test_live_link_written_by_mien_reads_back_by_column_name(tmp_path: Path) -> None:
    clip = tiny_weight_clip()
    text = arkit_csv.write(clip, io.BytesIO()).getvalue().decode()
    # Reorder the columns: the reader finds them by name, not position.
    rows = [line.split(",") for line in text.splitlines()]
    order = [0, 1, *reversed(range(2, len(rows[0])))]
    shuffled = tmp_path / "shuffled.csv"
    shuffled.write_text("\n".join(",".join(row[i] for i in order) for row in rows) + "\n")
    back = read_clip(shuffled)
    assert back.fps == 30.0 and back.n_frames == 3
    np.testing.assert_allclose(back.channel("jawOpen"), [0.0, 0.5, 1.0], atol=1e-12)
    np.testing.assert_allclose(back.channel("eyeBlinkLeft"), [1.0, 0.25, 0.0], atol=1e-12)
    np.testing.assert_allclose(back.channel("head_yaw_deg"), [0.0, 5.0, 10.0], atol=1e-9)


def test_live_link_from_the_app_with_a_60_fps_timecode(tmp_path: Path) -> None:
    header = "Timecode,BlendShapeCount," + ",".join(arkit_csv.COLUMNS)
    rows = []
    for i in range(70):  # 70 frames at 60 fps across a seconds boundary, starting mid-second
        frame = 50 + i
        seconds, ff = divmod(frame, 60)
        values = ["0"] * 61
        values[ARKIT_NAMES.index("jawOpen")] = f"{i / 69:.6f}"
        rows.append(f"20:05:{13 + seconds:02d}:{ff:02d}.{(i * 7) % 10}00,61," + ",".join(values))
    path = tmp_path / "take.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    clip = read_clip(path)
    assert clip.n_frames == 70 and clip.fps == pytest.approx(60.0, rel=0.02)
    assert clip.channel("jawOpen")[-1] == pytest.approx(1.0)
    from mien.rig.face_weights import weights_to_au

    au = weights_to_au(clip)
    assert max(au.channel("AU26")[-1], au.channel("AU27")[-1]) > 1.0  # jaw drop read back as an AU


def test_real_openface_csv(shared_data: Path) -> None:
    import pandas as pd

    path = shared_data / OPENFACE
    clip = read_clip(path)
    table = pd.read_csv(path, skipinitialspace=True)
    assert clip.n_frames == len(table) == 100
    steps = np.diff(table["timestamp"].to_numpy())
    assert clip.fps == pytest.approx(1.0 / steps.mean(), rel=1e-3)  # 1 ms steps in this file
    for row in (0, 1, 50, 98):
        for code in (1, 2, 4, 5, 23, 45):
            expected = table[f"AU{code:02d}_r"].iloc[row]
            for index in au_channels(code):  # both sides of a lateral AU
                assert clip.values[row, index] == pytest.approx(expected, abs=1e-9)
    assert clip.channel("AU1L")[0] == pytest.approx(0.6773) and clip.channel("AU5L")[50] == 0.0
    np.testing.assert_allclose(clip.channel("head_pitch_deg"), -np.degrees(table["pose_Rx"]), atol=1e-9)
    np.testing.assert_allclose(clip.channel("head_yaw_deg"), -np.degrees(table["pose_Ry"]), atol=1e-9)
    assert clip.channel("AU28").max() == 0.0  # AU28 only as presence: 0 in every row of this file


def test_openface_presence_only_au_and_lost_rows_are_reported(tmp_path: Path) -> None:
    path = tmp_path / "of.csv"
    path.write_text(
        "frame, timestamp, success, AU12_r, AU28_c, AU99_r\n"
        "1, 0.0, 1, 1.0, 1, 0\n2, 0.1, 0, 0.0, 0, 0\n3, 0.2, 1, 3.0, 0, 0\n"
    )
    with pytest.warns(UserWarning) as caught:
        clip = openface_csv.read(path)
    messages = " ".join(str(w.message) for w in caught)
    assert "AUs mien has no channel for: [99]" in messages and "1 of 3 rows without a face" in messages
    assert clip.channel("AU12L").tolist() == pytest.approx([1.0, 2.0, 3.0])  # the lost row filled between
    assert clip.channel("AU28")[0] == openface_csv.PRESENCE_INTENSITY


def test_openfacs_reads_sides_and_skips_unknown_keys(tmp_path: Path) -> None:
    path = tmp_path / "states.jsonl"
    path.write_text(
        '{"time_s": 0, "AU12": 2, "Speed": 0.1}\n\n'
        '{"time_s": 0.5, "AU12L": 4, "AU12R": 1, "mood": "happy", "head_yaw_deg": 5}\n'
    )
    with pytest.warns(UserWarning, match=r"mood \(line 3\)"):
        clip = openfacs_jsonl.read(path)
    assert clip.fps == 2.0 and clip.channel("AU12L").tolist() == [2.0, 4.0] and clip.channel("AU12R")[1] == 1.0
    assert clip.channel("head_yaw_deg")[1] == 5.0


LIVE_HEADER = "Timecode,BlendShapeCount," + ",".join(arkit_csv.COLUMNS)
LIVE_ROW = "00:00:00:{:02d}.000,61," + ",".join(["0.1"] * 61)
LL = LIVE_HEADER + "\n"
BAD_INPUT = [
    # (file name, text, error pattern: file, line, column)
    ("trunc.csv", "time_s,AU12L,AU6L\n0,1,2\n0.1,1", r"trunc\.csv line 3.*truncated"),
    ("nan.csv", "time_s,AU12L\n0,1\n0.1,nan\n", r"nan\.csv line 3 column 2 \(AU12L\)"),
    ("order.csv", "time_s,AU12L\n0,1\n0.2,1\n0.1,1\n", r"order\.csv line 4 column 1 \(time_s\)"),
    ("head.csv", "t,AU12L\n0,1\n", r"head\.csv line 1"),
    ("word.csv", "time_s,AU12L\n0,high\n", r"word\.csv line 2 column 2 \(AU12L\).*'high'"),
    ("ll_missing.csv", LIVE_HEADER.replace(",JawOpen", "") + "\n", r"ll_missing\.csv line 1.*JawOpen"),
    ("ll_trunc.csv", LIVE_HEADER + "\n" + LIVE_ROW.format(0) + "\n" + LIVE_ROW.format(1)[:80], r"line 3.*truncated"),
    (
        "ll_nan.csv",
        LIVE_HEADER + "\n" + LIVE_ROW.format(0).replace(",0.1", ",NaN", 1),
        r"line 2 column 3 \(EyeBlinkLeft\)",
    ),
    (
        "ll_order.csv",
        LIVE_HEADER + "\n" + LIVE_ROW.format(5) + "\n" + LIVE_ROW.format(3),
        r"line 3 column 1 \(Timecode\)",
    ),
    ("ll_range.csv", LIVE_HEADER + "\n" + LIVE_ROW.format(0).replace(",0.1", ",1.5", 1), r"line 2 column 3.*0\.\.1"),
    ("ll_tc.csv", LIVE_HEADER + "\n" + "12:99:00:00.000,61," + ",".join(["0"] * 61), r"line 2 column 1 \(Timecode\)"),
    ("of_missing.csv", "frame, timestamp, success\n1, 0, 1\n", r"of_missing\.csv line 1.*AU01_r"),
    ("of_nan.csv", "frame, timestamp, AU12_r\n1, 0.0, 1\n2, 0.1, -nan\n", r"of_nan\.csv line 3 column 3 \(AU12_r\)"),
    ("of_time.csv", "frame, timestamp, AU12_r\n1, 0.1, 1\n2, 0.1, 1\n", r"line 3 column 2 \(timestamp\)"),
    ("of_range.csv", "frame, timestamp, AU12_r\n1, 0.0, 7\n", r"line 2 column 3 \(AU12_r\).*0\.\.5"),
    ("of_pose.csv", "frame, timestamp, AU12_r, pose_Rx\n1, 0, 1, 0\n", r"pose_Ry"),
    ("of_lost.csv", "frame, timestamp, success, AU12_r\n1, 0, 0, 0\n", r"success.*found a face"),
    ("bad.jsonl", '{"time_s": 0, "AU12": 1}\n{"time_s": 0.1, "AU12": 1\n', r"bad\.jsonl line 2 column"),
    ("time.jsonl", '{"time_s": 0.5}\n{"time_s": 0.1}\n', r"time\.jsonl line 2 key time_s"),
    ("notime.jsonl", '{"AU12": 1}\n', r"notime\.jsonl line 1.*time_s"),
    ("nanau.jsonl", '{"time_s": 0, "AU12": NaN}\n', r"nanau\.jsonl line 1 key AU12"),
    ("range.jsonl", '{"time_s": 0, "AU12L": 9}\n', r"range\.jsonl line 1 key AU12L.*0\.\.5"),
    ("bad.json", '{"fps": 30, "channels": ["AU12L"],\n "values": [[1], [2]\n', r"bad\.json line 3 column 1"),
    ("nan.json", '{"fps": 30, "channels": ["AU12L"], "values": [[1], [NaN]]}', r"nan\.json values\[1, AU12L\]"),
    ("trunc.npz", "PK\x03\x04 not really a zip", r"trunc\.npz.*corrupt or truncated"),
]


@pytest.mark.parametrize(("name", "text", "pattern"), BAD_INPUT, ids=[b[0] for b in BAD_INPUT])
def test_bad_input_names_file_line_and_column(tmp_path: Path, name: str, text: str, pattern: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InvalidValueError, match=pattern):
        read_clip(path)


def test_live_link_unknown_columns_are_skipped_with_a_warning(tmp_path: Path) -> None:
    path = tmp_path / "extra.csv"
    path.write_text(LIVE_HEADER + ",MouthWobble\n" + LIVE_ROW.format(0) + ",0.3\n")
    with pytest.warns(UserWarning, match="skipped unknown columns MouthWobble"):
        clip = read_clip(path)
    assert "MouthWobble" not in clip.channels and clip.n_frames == 1


def test_missing_and_truncated_binary_files(tmp_path: Path) -> None:
    with pytest.raises(MissingAssetError, match="no such file"):
        read_clip(tmp_path / "absent.json")
    good = tmp_path / "good.npz"
    from mien.exchange import clip_npz

    clip_npz.write(tiny_face_clip(), good)
    cut = tmp_path / "cut.npz"
    cut.write_bytes(good.read_bytes()[:-40])
    with pytest.raises(InvalidValueError, match=r"cut\.npz.*corrupt or truncated"):
        read_clip(cut)
