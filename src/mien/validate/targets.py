"""The recognition targets, checked per head and identity: a scorecard a user can cite for a character.

mien holds its faces to these targets (issue "Faces that read", docs/VALIDATION.md). Each is a share of the
renders of :func:`~mien.validate.recognition.run_recognition` over both bases, distances and intensities, every
render judged by the averaged judge (:mod:`mien.validate.judge`: the classifier's probabilities averaged over twelve
crops). The targets depend on the kind of head:

* **realistic heads** (ICT-FaceKit and every character a user brings, :data:`TARGETS`): each of joy, sadness,
  anger, surprise and fear read as the top label in at least 90% of the frontal renders and 75% at 45 degrees;
  the neutral face read as neutral, frontally and at 45 degrees, in at least 90% (the 90-degree profile is
  reported, not targeted: the classifier was trained on frontal faces); each blend's top label one of its
  components in at least 90% of the frontal renders, as the study judged blends (the share whose top two labels
  are both components is reported beside it, without a bar);
* **the built-in head** (stylised, SPEC section 1; :data:`BUILTIN_TARGETS`): its own lower bars, each of the five
  frontally at least 80% and neutral read as neutral at least 75%; 45 degrees and the blends reported without a
  bar;
* every head: disgust taken for anger by the FACS reading (its detected AUs against the EMFACS prototypes) in at
  most 10% (the classifier almost never answers disgust, so it cannot judge it).

A target with no matching renders (a view or expression not asked for) is not checked. Each share comes with its
95% Wilson interval (a head has 8 frontal renders of each emotion: 7 of 8, 88%, cannot be told from 90% by so
few; the scorecard says so, "within noise"), its spread across crops (the same share judged by each of the
judge's readings alone, lowest to highest) and, for an emotion or a blend, the second judge on the same renders:
how many the FACS reading (:mod:`mien.validate.facs_reading`) reads as the emotion or one of the blend's
components. A miss the FACS reading does not share is the classifier's alone (docs/VALIDATION.md); the bar stays
the classifier's.

>>> [t.name for t in TARGETS][:2]
['frontal joy', 'frontal sadness']
>>> [t.rule for t in BUILTIN_TARGETS][:6]
['>= 80%', '>= 80%', '>= 80%', '>= 80%', '>= 80%', 'reported']
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mien.render.camera import VIEWS
from mien.rig.heads import head_label
from mien.validate.expressions import BASICS, EXPRESSIONS, blend_components
from mien.validate.statistics import wilson_interval

__all__ = [
    "BUILTIN_TARGETS",
    "FRONTAL",
    "LATERAL",
    "OBLIQUE",
    "TARGETS",
    "Target",
    "TargetCheck",
    "check_targets",
    "head_kind",
    "scorecard_lines",
    "targets_for",
]

FRONTAL: tuple[str, ...] = tuple(name for name, view in VIEWS.items() if view.angle == "frontal")
"""The frontal views of :data:`mien.render.camera.VIEWS` (the targets' first condition)."""
OBLIQUE: tuple[str, ...] = tuple(name for name, view in VIEWS.items() if view.angle == "oblique")
"""The 45-degree views."""
LATERAL: tuple[str, ...] = tuple(name for name, view in VIEWS.items() if view.angle == "lateral")
"""The 90-degree profiles (reported, not targeted: the classifier was trained on frontal faces)."""

_STUDY_BLENDS = tuple(name for name in EXPRESSIONS if blend_components(name) is not None)


@dataclass(frozen=True)
class Target:
    """One target: a share measured on a recognition result, and the bound it must meet."""

    name: str
    """Short name, e.g. ``"frontal joy"``."""
    bound: float | None
    """The share it must reach (or stay under, with :attr:`at_most`), 0..1; None: reported without a bar."""
    outcomes: Callable[..., list[bool]]
    """``outcomes(result, reading=None, **conditions)`` -> one bool per judged render (the share is their mean);
    ``reading``: judged by that one crop of the averaged judge alone."""
    at_most: bool = False
    """True when the share must stay at or below :attr:`bound`."""
    second: Callable[..., list[bool]] | None = None
    """``second(result, **conditions)`` -> one bool per render the FACS reading judged: read as the expression (a
    blend: one of its components); None where the FACS reading has no say (neutral, disgust's own target)."""

    def met(self, value: float) -> bool | None:
        """Whether ``value`` meets the bound (None for nan, not measured, or for a target without a bar)."""
        if value != value or self.bound is None:
            return None
        return value <= self.bound if self.at_most else value >= self.bound

    @property
    def rule(self) -> str:
        """``">= 90%"``, ``"<= 10%"`` or ``"reported"`` (no bar)."""
        if self.bound is None:
            return "reported"
        return f"{'<=' if self.at_most else '>='} {self.bound:.0%}"


def _recognised(**fixed: Any) -> Callable[..., list[bool]]:
    def outcomes(result: Any, reading: str | None = None, **conditions: Any) -> list[bool]:
        judged = (s.correct(reading=reading) for s in result.subset(**fixed, **conditions))
        return [bool(j) for j in judged if j is not None]

    return outcomes


def _both_components(**fixed: Any) -> Callable[..., list[bool]]:
    def outcomes(result: Any, reading: str | None = None, **conditions: Any) -> list[bool]:
        judged = (s.both_components(reading=reading) for s in result.subset(**fixed, **conditions))
        return [bool(j) for j in judged if j is not None]

    return outcomes


def _read_by_facs(**fixed: Any) -> Callable[..., list[bool]]:
    def outcomes(result: Any, **conditions: Any) -> list[bool]:
        return [agrees for s in result.subset(**fixed, **conditions) if (agrees := s.facs_agrees()) is not None]

    return outcomes


def _disgust_as_anger(result: Any, reading: str | None = None, **conditions: Any) -> list[bool]:
    scores = result.subset(expression="disgust", **conditions)
    return [agrees for s in scores if (agrees := s.facs_agrees("anger")) is not None]


def _targets(five: float, oblique: float | None, neutral: float, blends: float | None) -> tuple[Target, ...]:
    return (
        *(
            Target(f"frontal {name}", five, _recognised(**frontal), second=_read_by_facs(**frontal))
            for name in BASICS
            for frontal in [{"expression": name, "view": FRONTAL}]
        ),
        Target(
            "45 degrees, the five",
            oblique,
            _recognised(expression=BASICS, view=OBLIQUE),
            second=_read_by_facs(expression=BASICS, view=OBLIQUE),
        ),
        Target("neutral reads neutral", neutral, _recognised(expression="neutral", view=FRONTAL + OBLIQUE)),
        Target("disgust read as anger (FACS reading)", 0.10, _disgust_as_anger, at_most=True),
        *(
            Target(
                f"blend {name} (top label a component)",
                blends,
                _recognised(expression=name, view=FRONTAL),
                second=_read_by_facs(expression=name, view=FRONTAL),
            )
            for name in _STUDY_BLENDS
        ),
        *(
            Target(f"blend {name} (top two both components)", None, _both_components(expression=name, view=FRONTAL))
            for name in _STUDY_BLENDS
        ),
    )


TARGETS: tuple[Target, ...] = _targets(0.90, 0.75, 0.90, 0.90)
"""The targets of a realistic head (ICT-FaceKit, a user's character), in the order the scorecard shows them."""

BUILTIN_TARGETS: tuple[Target, ...] = _targets(0.80, None, 0.75, None)
"""The built-in head's own bars (it is stylised, SPEC section 1): each of the five frontally >= 80%, neutral reads
neutral >= 75%, disgust as anger <= 10%; 45 degrees and the blends reported without a bar."""


def head_kind(head: str) -> str:
    """``"builtin"`` for mien's built-in head, ``"realistic"`` for every other (ICT-FaceKit, a user's file)."""
    return "builtin" if head == "builtin" else "realistic"


def targets_for(head: str) -> tuple[Target, ...]:
    """:data:`BUILTIN_TARGETS` for the built-in head, :data:`TARGETS` for a realistic one."""
    return BUILTIN_TARGETS if head_kind(head) == "builtin" else TARGETS


@dataclass(frozen=True)
class TargetCheck:
    """One target measured on one head and identity (or on all of them: ``head`` ``"all"``)."""

    head: str
    """``"ict:a"``, ``"builtin:default"``... or ``"all"``."""
    target: Target
    """What was checked."""
    hits: int
    """Judged renders that count toward the share."""
    n: int
    """Judged renders (0: not measured)."""
    spread: tuple[float, float] = (float("nan"), float("nan"))
    """``(lowest, highest)`` share judged by each crop of the averaged judge alone (nan without readings)."""
    second: tuple[int, int] = (0, 0)
    """``(hits, judged)`` of the FACS reading on the same renders (:attr:`Target.second`; (0, 0): no say)."""

    @property
    def value(self) -> float:
        """The measured share (nan: no render matched)."""
        return self.hits / self.n if self.n else float("nan")

    @property
    def met(self) -> bool | None:
        """Whether the target is met (None: not measured)."""
        return self.target.met(self.value)

    @property
    def interval(self) -> tuple[float, float]:
        """95% Wilson interval of :attr:`value` (:func:`~mien.validate.statistics.wilson_interval`)."""
        return wilson_interval(self.hits, self.n)

    @property
    def decided(self) -> bool:
        """True when the whole 95% interval lies on one side of the bound: more renders would not likely
        change the verdict (8 renders at 7 of 8 leave 53-98%, which straddles a 90% bound)."""
        low, high = self.interval
        return self.target.bound is None or not low <= self.target.bound <= high

    def describe(self) -> str:
        """``"frontal joy 88% (7 of 8; 95% interval 53-98%; crops 75-100%; FACS reading 8 of 8; >= 90%)"`` (no
        crop spread without readings, no FACS reading where it has no say)."""
        low, high = self.interval
        share = f"{self.value:.0%} ({self.hits} of {self.n}; 95% interval {round(low * 100)}-{high:.0%}"
        if self.spread[0] == self.spread[0]:
            share += f"; crops {round(self.spread[0] * 100)}-{self.spread[1]:.0%}"
        if self.second[1]:
            share += f"; FACS reading {self.second[0]} of {self.second[1]}"
        return f"{self.target.name} {share}; {self.target.rule})"


def check_targets(result: Any) -> tuple[TargetCheck, ...]:
    """Every target of each head's kind (:func:`targets_for`) on every head and identity of ``result``, then on
    all the heads of each kind together (``"all"`` when there is one kind, else ``"all realistic"`` and ``"all
    built-in"``)."""
    heads = sorted({(s.stimulus.head, s.stimulus.identity) for s in result.scores})
    kinds = {kind: [h for h in heads if head_kind(h[0]) == kind] for kind in ("realistic", "builtin")}
    kinds = {kind: members for kind, members in kinds.items() if members}
    readings = tuple(getattr(result, "readings", ()))
    checks = []
    for kind, members in kinds.items():
        label = "all" if len(kinds) == 1 else ("all realistic" if kind == "realistic" else "all built-in")
        groups = [(head_label(h, i), [(h, i)]) for h, i in members] + [(label, members)]
        for target in BUILTIN_TARGETS if kind == "builtin" else TARGETS:
            for name, group in groups:
                outcomes: list[bool] = []
                second: list[bool] = []
                per_reading: list[list[bool]] = [[] for _ in readings]
                for h, i in group:
                    outcomes += target.outcomes(result, head=h, identity=i)
                    if target.second is not None:
                        second += target.second(result, head=h, identity=i)
                    for k, reading in enumerate(readings):
                        per_reading[k] += target.outcomes(result, reading=reading, head=h, identity=i)
                shares = [sum(r) / len(r) for r in per_reading if r]
                spread = (min(shares), max(shares)) if shares else (float("nan"), float("nan"))
                agreed = (sum(second), len(second))
                checks.append(TargetCheck(name, target, sum(outcomes), len(outcomes), spread, agreed))
    return tuple(checks)


def scorecard_lines(checks: tuple[TargetCheck, ...]) -> list[str]:
    """Per head: how many measured targets it meets, then each miss with its figure and 95% interval (a miss whose
    interval reaches the bound is marked "within noise": too few renders to tell).

    >>> from mien.validate.targets import TARGETS, TargetCheck
    >>> joy = TARGETS[0]
    >>> for line in scorecard_lines((TargetCheck("ict:a", joy, 8, 8), TargetCheck("all", joy, 70, 100))):
    ...     print(line)
      ict:a             meets 1 of 1
      all               meets 0 of 1; misses:
        frontal joy 70% (70 of 100; 95% interval 60-78%; >= 90%)
    """
    lines = []
    for head in dict.fromkeys(check.head for check in checks):
        measured = [c for c in checks if c.head == head and c.met is not None]
        missed = [c for c in measured if not c.met]
        lines.append(
            f"  {head:17s} meets {len(measured) - len(missed)} of {len(measured)}" + ("; misses:" if missed else "")
        )
        lines.extend(f"    {c.describe()}{'' if c.decided else ', within noise'}" for c in missed)
        reported = [c for c in checks if c.head == head and c.target.bound is None and c.n]
        lines.extend(f"    reported: {c.describe()}" for c in reported)
    return lines
