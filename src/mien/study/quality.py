"""Broekens' recognition quality: the share of the perceived intensity that went to the intended label.

Broekens, Qu & Brinkman (Table 4) define, per expression,

    quality = target_intensity / (mean_intensity x number_of_labels)

where *target intensity* is the mean perceived intensity of the label the expression portrays (joy for a joy
face) and *mean intensity* the mean over all ten labels. Table 4's own columns satisfy it as a ratio of the
means over every rating (afraid: 0.531 / (0.092 x 10) = 0.577, printed 0.576), so that is what
:func:`quality_table` computes: means over all complete trials (one trial = one participant rating one
stimulus), then the ratio. It equals the share of the summed label intensities that the target label got.

The paper's intensities run 0..1 with 0 = not perceived (joy's mean over labels is 0.063), so a 5-point rating
``r`` in 1..5 enters as intensity ``(r - 1) / 4`` (:func:`label_intensity`). The ratio does not depend on the
scale but does on the zero: raw 1..5 ratings would give an all-"not at all" trial a quality of 0.1, the
paper's scale gives it none.

The paper's own figures are in ``mien/affect/data/broekens_table4.csv`` (:func:`paper_table4`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from mien.affect.emotions import resolve_emotion
from mien.errors import UnknownNameError
from mien.fileio.tables import read_table

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "LABEL_PREFIX",
    "label_intensity",
    "label_question",
    "paper_table4",
    "quality_table",
    "table_frame",
]

LABEL_PREFIX = "label:"
"""Prefix of the ``question`` value of an emotion-label rating (``"label:joy"``)."""


def label_intensity(rating: np.ndarray | float) -> np.ndarray:
    """Perceived intensity 0..1 of a 5-point rating 1..5 (1 = not perceived -> 0, 5 -> 1).

    >>> label_intensity(np.array([1, 3, 5])).tolist()
    [0.0, 0.5, 1.0]
    """
    return (np.asarray(rating, dtype=np.float64) - 1.0) / 4.0


def label_question(expression: str) -> str:
    """The ``question`` naming the label an expression portrays (aliases resolved: ``"happy"`` -> ``"label:joy"``).

    >>> label_question("afraid")
    'label:fear'
    """

    try:
        return LABEL_PREFIX + resolve_emotion(expression)
    except UnknownNameError:
        return LABEL_PREFIX + str(expression)


def quality_table(trials: pd.DataFrame, labels: Sequence[str], by: Sequence[str] = ()) -> pd.DataFrame:
    """Quality per expression (and per level of the ``by`` columns), the paper's Table 4 for ``trials``.

    ``trials``: one row per complete trial with an ``expression`` column and one column per label question
    in ``labels`` (``"label:joy"``...) holding the rating 1..5. Returns one row per group with columns
    ``[*by, "expression", "n_trials", "target_intensity", "mean_intensity", "quality"]``: intensities 0..1
    (:func:`label_intensity`), quality = target / (mean x len(labels)); NaN where the expression's own label
    was not rated (a neutral face has none).

    >>> import pandas as pd
    >>> t = pd.DataFrame({"expression": ["joy", "joy"], "label:joy": [5, 4], "label:sadness": [1, 2]})
    >>> quality_table(t, ["label:joy", "label:sadness"])[["target_intensity", "quality"]].round(4).values.tolist()
    [[0.875, 0.875]]
    """
    import pandas as pd

    label_list = list(labels)
    intensity = pd.DataFrame(label_intensity(trials[label_list].to_numpy()), columns=label_list, index=trials.index)
    keys = [*by, "expression"]
    rows = []
    for key, group in trials.groupby(keys, sort=True, observed=True):
        values = intensity.loc[group.index]
        expression = str(group["expression"].iloc[0])
        target_column = label_question(expression)
        mean = float(values.to_numpy().mean())
        target = float(values[target_column].mean()) if target_column in label_list else float("nan")
        quality = target / (mean * len(label_list)) if mean > 0 else float("nan")
        key_values = key if isinstance(key, tuple) else (key,)
        rows.append([*key_values, len(group), target, mean, quality])
    return pd.DataFrame(rows, columns=[*keys, "n_trials", "target_intensity", "mean_intensity", "quality"])


def paper_table4() -> pd.DataFrame:
    """Broekens et al.'s Table 4 (19 participants): ``expression, paper_label, average, target, quality``.

    >>> paper_table4().set_index("expression").loc["joy", "quality"]
    np.float64(0.806)
    """
    return table_frame("mien.affect", "data/broekens_table4.csv")


def table_frame(package: str, name: str) -> pd.DataFrame:
    """A data table of mien (:func:`mien.fileio.tables.read_table`) as a DataFrame, numeric columns as numbers."""
    import pandas as pd

    frame = pd.DataFrame(read_table(package, name))
    for column in frame.columns:
        try:
            frame[column] = pd.to_numeric(frame[column])
        except ValueError:  # a text column stays text
            pass
    return frame
