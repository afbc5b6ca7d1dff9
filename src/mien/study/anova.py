"""Repeated-measures ANOVA over within-subject factors: :func:`rm_anova` -> :class:`AnovaTable`.

Each participant contributes one value per cell (the mean of their trials in it). A participant without a
value in every cell is dropped and named (a balanced design is what the test needs). One or two factors go
to pingouin's ``rm_anova`` (F, df, p, Greenhouse-Geisser epsilon and p, generalised eta squared); three or
more (the Broekens design has four) to :func:`balanced_rm_anova`, the textbook computation on the
participants x cells array (orthonormal contrasts per effect), which gives the same for any number of
factors in milliseconds where statsmodels' ``AnovaRM`` (uncorrected, no epsilon) takes a second per measure.
The tests hold the two against each other and against ``AnovaRM`` (F, df, p to 1e-6).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mien.extras import require

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["AnovaTable", "balanced_rm_anova", "rm_anova"]

COLUMNS = ("effect", "F", "df1", "df2", "p", "p_gg", "eps", "ng2")
"""Columns of :attr:`AnovaTable.table`."""


@dataclass(frozen=True, eq=False)
class AnovaTable:
    """One repeated-measures ANOVA: a dependent measure over within-subject factors."""

    measure: str
    """The dependent measure (``"target_intensity"``, ``"naturalness"``, ``"label:joy"``, ``"feels_right"``...)."""
    factors: tuple[str, ...]
    """The within-subject factors."""
    table: pd.DataFrame
    """One row per effect (:data:`COLUMNS`): ``effect`` (factors joined by ``" x "``), ``F``, ``df1``, ``df2``,
    ``p`` (uncorrected), ``p_gg`` and ``eps`` (Greenhouse-Geisser), ``ng2`` (generalised eta squared). Empty
    when the test could not run (see :attr:`note`)."""
    engine: str
    """``"pingouin.rm_anova"`` or ``"mien.study.anova.balanced_rm_anova"`` (``""`` when it did not run)."""
    n_participants: int
    """Participants in the test (every cell filled)."""
    dropped: tuple[str, ...] = ()
    """Participants left out because some cell of theirs had no answer."""
    note: str = ""
    """Why the test did not run, or what was left out; empty when nothing was."""


def _contrasts(levels: int) -> np.ndarray:
    """(levels, levels - 1) orthonormal columns orthogonal to the constant."""
    centring = np.eye(levels) - 1.0 / levels
    u, _, _ = np.linalg.svd(centring)
    return np.asarray(u[:, : levels - 1])


def balanced_rm_anova(values: np.ndarray, names: Sequence[str]) -> pd.DataFrame:
    """Fully within-subject ANOVA of ``values`` ((n_subjects, L1, ..., Lk) float, every cell filled).

    ``names``: the k factor names. Returns one row per effect (main effects, then interactions by order, as
    statsmodels lists them) with :data:`COLUMNS`. For effect E with orthonormal contrasts C (the Kronecker
    product of each factor's), T = (subject means over the other factors) @ C; SS_E = m n |mean(T)|^2 and
    SS_error = m |T - mean(T)|^2 (m = cells per level of E), F = (SS_E / df) / (SS_error / (df (n - 1))).
    Greenhouse-Geisser eps = tr(S)^2 / (df tr(S^2)) with S the covariance of T; ng2 = SS_E / (SS_E +
    SS_subjects + every SS_error) (Olejnik & Algina, all factors manipulated).
    """
    import pandas as pd
    from scipy import stats

    data = np.asarray(values, dtype=np.float64)
    n = data.shape[0]
    shape = data.shape[1:]
    k = len(shape)
    total_cells = math.prod(shape)
    effects = [e for order in range(1, k + 1) for e in itertools.combinations(range(k), order)]
    rows = []
    errors = 0.0
    for effect in effects:
        others = tuple(1 + a for a in range(k) if a not in effect)
        marginal = data.mean(axis=others) if others else data  # (n, L_e1, L_e2, ...)
        contrast = _contrasts(shape[effect[0]])
        for axis in effect[1:]:
            contrast = np.kron(contrast, _contrasts(shape[axis]))
        scores = marginal.reshape(n, -1) @ contrast  # (n, df)
        df = contrast.shape[1]
        per_cell = total_cells // math.prod(shape[a] for a in effect)
        centre = scores.mean(axis=0)
        ss_effect = per_cell * n * float(centre @ centre)
        ss_error = per_cell * float(((scores - centre) ** 2).sum())
        errors += ss_error
        covariance = np.atleast_2d(np.cov(scores, rowvar=False, ddof=1))
        trace = float(np.trace(covariance))
        eps = 1.0 if df == 1 else trace**2 / (df * float(np.trace(covariance @ covariance))) if trace > 0 else np.nan
        rows.append([" x ".join(names[a] for a in effect), ss_effect, ss_error, df, df * (n - 1), eps])
    subject_means = data.reshape(n, -1).mean(axis=1)
    ss_subjects = total_cells * float(((subject_means - subject_means.mean()) ** 2).sum())
    out = []
    for name, ss_effect, ss_error, df1, df2, eps in rows:
        with np.errstate(divide="ignore", invalid="ignore"):
            f_value = (ss_effect / df1) / (ss_error / df2) if ss_error > 0 else np.nan
        p = float(stats.f.sf(f_value, df1, df2)) if np.isfinite(f_value) else np.nan
        p_gg = float(stats.f.sf(f_value, df1 * eps, df2 * eps)) if np.isfinite(f_value) and np.isfinite(eps) else np.nan
        denominator = ss_effect + ss_subjects + errors
        ng2 = ss_effect / denominator if denominator > 0 else np.nan
        out.append([name, f_value, float(df1), float(df2), p, p_gg, eps, ng2])
    return pd.DataFrame(out, columns=list(COLUMNS))


def rm_anova(trials: pd.DataFrame, measure: str, factors: Sequence[str], subject: str = "participant") -> AnovaTable:
    """Repeated-measures ANOVA of ``measure`` over the within-subject ``factors`` (see the module docstring).

    ``trials`` has a ``subject`` column, the ``factors`` columns and the ``measure`` column; each
    participant's values are averaged per cell, participants missing a cell are dropped (and named). Factors
    with one level are left out (noted). Never raises for the data's shape: a test that cannot run gives an
    empty table with a :attr:`~AnovaTable.note`.
    """
    import pandas as pd

    empty = pd.DataFrame(columns=list(COLUMNS))
    data = trials[[subject, *factors, measure]].dropna(subset=[measure])
    data = data.assign(**{measure: data[measure].astype(np.float64), subject: data[subject].astype(str)})
    notes = []
    used = [f for f in factors if data[f].nunique() > 1]
    if len(used) < len(factors):
        notes.append(f"one level only, left out: {', '.join(f for f in factors if f not in used)}")
    if not used:
        return AnovaTable(measure, tuple(factors), empty, "", 0, (), "no factor with two levels")
    cells = data.groupby([subject, *used], observed=True)[measure].mean()
    levels = [sorted(set(cells.index.get_level_values(f))) for f in used]
    counts = cells.groupby(level=0).size()
    n_cells = math.prod(len(lvl) for lvl in levels)
    complete = sorted(str(s) for s in counts.index[counts == n_cells])
    dropped = tuple(sorted(str(s) for s in counts.index[counts != n_cells]))
    if dropped:
        notes.append(f"{len(dropped)} participant(s) without an answer in every cell dropped: {', '.join(dropped)}")
    if len(complete) < 2:
        notes.append(f"{len(complete)} participant(s) with every cell: the test needs at least 2")
        return AnovaTable(measure, tuple(used), empty, "", len(complete), dropped, "; ".join(notes))
    cells = cells[cells.index.get_level_values(0).isin(complete)]
    if len(used) <= 2:
        table = _pingouin(cells.reset_index(), subject, used, measure)
        engine = "pingouin.rm_anova"
    else:
        grid = pd.MultiIndex.from_product([complete, *levels])
        values = cells.reindex(grid).to_numpy(np.float64).reshape(len(complete), *[len(lvl) for lvl in levels])
        table = balanced_rm_anova(values, used)
        engine = "mien.study.anova.balanced_rm_anova"
    return AnovaTable(measure, tuple(used), table[list(COLUMNS)], engine, len(complete), dropped, "; ".join(notes))


def _pingouin(cells: pd.DataFrame, subject: str, used: list[str], measure: str) -> pd.DataFrame:
    import warnings

    pingouin = require("pingouin", "study")
    from scipy import stats

    safe = {f: f"factor{i}" for i, f in enumerate(used)}  # a level named like the measure breaks pingouin's melt
    back = {v: k for k, v in safe.items()}
    frame = cells.rename(columns={**safe, measure: "dv", subject: "subject"})
    within = list(safe.values())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # constant cells, tiny samples: the numbers say it
        result = pingouin.rm_anova(
            frame, dv="dv", within=within if len(within) > 1 else within[0], subject="subject", correction=True
        )
    out = result.rename(columns={"ddof1": "df1", "ddof2": "df2", "p_unc": "p", "p_GG_corr": "p_gg"})
    out["effect"] = [" x ".join(back.get(p.strip(), p.strip()) for p in str(s).split("*")) for s in out["Source"]]
    for column in ("F", "df1", "df2", "p", "p_gg", "eps", "ng2"):  # no variance: pingouin leaves F and p out
        out[column] = out[column].astype(np.float64) if column in out.columns else np.nan
    for i in out.index:  # rm_anova leaves the one-way GG p out when sphericity holds; compute it the same way
        if not np.isfinite(out.at[i, "p_gg"]) and np.isfinite(out.at[i, "eps"]) and np.isfinite(out.at[i, "F"]):
            eps = float(out.at[i, "eps"])
            out.at[i, "p_gg"] = float(stats.f.sf(out.at[i, "F"], out.at[i, "df1"] * eps, out.at[i, "df2"] * eps))
    return out.reset_index(drop=True)
