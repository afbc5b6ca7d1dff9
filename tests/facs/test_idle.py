import numpy as np
import pytest

from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.idle import EYELID_WALK, MOUTH_WALK, NECK_WALK, Idle, IdleBatch, IdleSettings

AU45L = FACE_CHANNELS.index("AU45L")
ONLY_BLINK = IdleSettings(mouth=False, eyelids=False, neck=False, gaze=False, wobble=False)


@pytest.mark.slow
def test_blink_intervals_follow_normal_6_2_over_a_long_run():
    idle = Idle(seed=11, settings=ONLY_BLINK)
    starts, closed, previous = [], False, 0.0
    fps = 100.0
    for i in range(int(4000 * fps)):  # 4000 s, ~660 blinks
        level = idle.blink(i / fps)
        if level > 0.0 and previous == 0.0:
            starts.append(i / fps)
        previous = level
        closed = closed or level > 0.99
    intervals = np.diff(starts)
    assert len(intervals) > 600
    assert abs(intervals.mean() - 6.0) < 0.2
    assert abs(intervals.std() - 2.0) < 0.2
    assert closed


def test_each_blink_lasts_360_ms_and_closes_at_e():
    idle = Idle(seed=3, settings=ONLY_BLINK)
    fps = 1000.0
    levels = np.array([idle.blink(i / fps) for i in range(int(30 * fps))])
    runs = np.diff(np.concatenate([[0], (levels > 0).astype(int), [0]]))
    durations = (np.flatnonzero(runs == -1) - np.flatnonzero(runs == 1)) / fps
    assert len(durations) >= 3
    np.testing.assert_allclose(durations, 0.36, atol=0.0021)
    frame = np.zeros(len(FACE_CHANNELS))
    idle2 = Idle(seed=3, settings=ONLY_BLINK)
    peak = 0.0
    for i in range(int(30 * fps)):
        frame[:] = 0.0
        idle2.apply(i / fps, frame)
        peak = max(peak, frame[AU45L])
    assert peak == pytest.approx(5.0, abs=0.03)


@pytest.mark.slow
@pytest.mark.parametrize(("walk_index", "spec"), [(0, MOUTH_WALK), (2, EYELID_WALK), (3, NECK_WALK)])
def test_random_walks_stay_bounded_and_step_with_the_papers_probabilities(walk_index, spec):
    idle = Idle(seed=5)
    n = 60000
    positions = np.array([idle.walk_positions((k + 1) / idle.settings.tick_hz)[walk_index] for k in range(n)])
    assert positions.min() >= -1.0 and positions.max() <= 1.0
    before = np.concatenate([[0.0], positions[:-1]])
    step = positions - before
    ups = np.isclose(step, spec.step)
    downs = np.isclose(step, -spec.step)
    # interior positions only (at the bounds a step is clamped)
    interior = np.abs(before) < 1.0 - spec.step
    assert (ups | downs)[interior].mean() == pytest.approx(spec.move_probability, abs=0.02)
    for lo, hi in ((-0.6, -0.2), (-0.2, 0.2), (0.2, 0.6)):
        sel = interior & (before >= lo) & (before < hi) & (ups | downs)
        if sel.sum() < 2000:
            continue
        expected = np.mean([spec.up_probability(m) for m in before[sel]])
        assert ups[sel].mean() == pytest.approx(expected, abs=0.03)


def test_idle_parts_switch_off_one_by_one():
    frame = np.zeros(len(FACE_CHANNELS))
    Idle(
        seed=1, settings=IdleSettings(blink=False, mouth=False, eyelids=False, neck=False, gaze=False, wobble=False)
    ).apply(3.0, frame)
    assert not frame.any()
    frame[:] = 0
    Idle(seed=1, settings=IdleSettings(blink=False, mouth=False, eyelids=False, neck=False, gaze=False)).apply(
        3.0, frame
    )
    moved = {FACE_CHANNELS[i] for i in np.flatnonzero(frame)}
    assert moved == {"head_yaw_deg", "head_roll_deg"}


def test_batch_idle_equals_single_idle_per_seed():
    seeds = np.array([4, 9, 123])
    batch = IdleBatch(seeds)
    singles = [Idle(int(s)) for s in seeds]
    frames = np.zeros((3, len(FACE_CHANNELS)))
    for i in range(1, 1200):
        t = i / 30.0
        frames[:] = 0.0
        batch.apply(t, frames)
        for k, single in enumerate(singles):
            frame = np.zeros(len(FACE_CHANNELS))
            single.apply(t, frame)
            np.testing.assert_allclose(frames[k], frame, atol=1e-12)


def test_same_seed_same_face_different_seed_different_face():
    def run(seed):
        idle, out = Idle(seed), []
        for i in range(600):
            frame = np.zeros(len(FACE_CHANNELS))
            idle.apply(i / 60, frame)
            out.append(frame)
        return np.array(out)

    assert np.array_equal(run(1), run(1))
    assert not np.array_equal(run(1), run(2))


def _reference_walks(seed: int, n_ticks: int) -> np.ndarray:
    """The paper's walks tick by tick in plain Python, from the same counter-based draws (the pre-batch stream)."""
    from mien.facs.counter_random import uniform

    walks = (MOUTH_WALK, MOUTH_WALK, EYELID_WALK, NECK_WALK, NECK_WALK)
    m = [0.0] * 5
    out = []
    for tick in range(n_ticks):
        for w, spec in enumerate(walks):
            if float(uniform(seed, 2 * w, tick)) < spec.move_probability:
                up = float(uniform(seed, 2 * w + 1, tick)) < spec.up_probability(m[w])
                m[w] = min(1.0, max(-1.0, m[w] + (spec.step if up else -spec.step)))
        out.append(list(m))
    return np.array(out)


def test_walks_keep_the_seeded_stream_across_the_old_block_boundary():
    idle = Idle(seed=21)
    ticks = 1100  # past 512 and 1024, where the walks used to be recomputed a block at a time
    positions = np.array([idle.walk_positions((k + 1) / 60.0) for k in range(ticks)])
    np.testing.assert_array_equal(positions, _reference_walks(21, ticks))


def test_every_step_draws_the_same_amount_of_randomness(monkeypatch):
    """No step of a batch computes ahead: each 60 Hz step advances the walks one tick, one draw of (n, 10) uniforms.

    A batch of one row draws 16 ticks at a time instead (numpy's cost per call, not per number, dominates it).
    """
    import mien.facs.idle as idle_module

    sizes: list[int] = []
    real = idle_module.uniform_from_keys

    def counting(keys, counter):
        values = real(keys, counter)
        sizes.append(values.size)
        return values

    monkeypatch.setattr(idle_module, "uniform_from_keys", counting)
    block = idle_module._DRAW_BLOCK
    assert block == 16
    for n_rows, expected in ((4, {4 * 10}), (1, {0, block * 10})):
        batch = IdleBatch(np.arange(n_rows), IdleSettings(blink=False, gaze=False))
        frames = np.zeros((n_rows, len(FACE_CHANNELS)))
        per_step = []
        for i in range(1, 1200):
            sizes.clear()
            batch.apply(i / 60.0, frames)
            per_step.append(sum(sizes))
        assert set(per_step) == expected
        assert sum(per_step) == (n_rows * 10 * 1199 if n_rows > 1 else block * 10 * 75)  # ticks 0..1198


def test_a_row_of_one_equals_a_row_of_a_batch_at_any_step_times():
    """The one-row path (Python floats, draws in blocks) gives the vectorised path's numbers, bit for bit."""
    rng = np.random.default_rng(3)
    for seed in (0, 7):
        one, two = IdleBatch(np.array([seed])), IdleBatch(np.array([seed, seed + 1]))
        frame_one, frames_two = np.zeros((1, len(FACE_CHANNELS))), np.zeros((2, len(FACE_CHANNELS)))
        t = 0.0
        for _ in range(4000):
            t += float(rng.choice([1 / 60, 1 / 30, 0.0, 0.4, 1 / 144]))
            frame_one[:] = frames_two[0] = rng.uniform(0.0, 2.0, len(FACE_CHANNELS))
            mouth_scale = float(rng.uniform())
            one.apply(t, frame_one, mouth_scale)
            two.apply(t, frames_two, np.array([mouth_scale, 1.0]))
            np.testing.assert_array_equal(frame_one[0], frames_two[0])
        assert one.walk_positions(t).tolist() == two.walk_positions(t)[:1].tolist()


def test_rows_with_their_own_settings_equal_single_idles():
    settings = [IdleSettings(), IdleSettings(blink=False, tick_hz=30.0), None, IdleSettings(gaze_yaw_deg=20.0)]
    batch = IdleBatch(np.zeros(0, int))
    for seed, s in enumerate(settings):
        batch.add_rows(np.array([seed + 3]), s)
    singles = [Idle(seed + 3, s) if s is not None else None for seed, s in enumerate(settings)]
    frames = np.zeros((4, len(FACE_CHANNELS)))
    for i in range(1, 900):
        t = i / 45.0
        frames[:] = 0.0
        batch.apply(t, frames)
        for k, single in enumerate(singles):
            frame = np.zeros(len(FACE_CHANNELS))
            if single is not None:
                single.apply(t, frame)
            np.testing.assert_allclose(frames[k], frame, atol=1e-12)
    assert not frames[2].any()
