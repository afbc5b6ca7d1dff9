"""Optional dependencies: require/available, and EXTRA_OF agrees with the extras pyproject.toml declares."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from mien.errors import MissingExtraError
from mien.extras import EXTRA_OF, available, require

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"

MODULE_OF_DISTRIBUTION = {"pillow": "PIL", "imageio-ffmpeg": "imageio_ffmpeg", "ai-edge-litert": "ai_edge_litert"}
"""Distributions whose import name differs from their name on PyPI."""


def _extras() -> dict[str, set[str]]:
    """Extra -> the top-level modules its requirements install (``dask[distributed]`` gives dask and distributed)."""
    table = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    out: dict[str, set[str]] = {}
    for extra, requirements in table.items():
        modules = set()
        for requirement in requirements:
            match = re.match(r"([A-Za-z0-9_.-]+)(?:\[([^\]]+)\])?", requirement)
            assert match is not None, requirement
            name, options = match.group(1), match.group(2)
            if name == "mien":
                continue
            modules.add(MODULE_OF_DISTRIBUTION.get(name, name))
            if name == "dask" and options == "distributed":
                modules.add("distributed")
        out[extra] = modules
    return out


def test_every_extra_of_the_table_installs_its_module() -> None:
    extras = _extras()
    wrong = {module: extra for module, extra in EXTRA_OF.items() if module not in extras.get(extra, set())}
    assert wrong == {}


def test_every_module_an_extra_installs_has_an_entry() -> None:
    declared = set().union(*_extras().values()) - {"pytest", "ruff", "mypy"}
    dev = _extras()["dev"]
    assert sorted(declared - dev - set(EXTRA_OF)) == []


def test_the_table_names_the_smallest_extra_except_pillow() -> None:
    extras = {name: modules for name, modules in _extras().items() if name not in ("all", "dev")}
    smallest = {m: min((e for e in extras if m in extras[e]), key=lambda e: len(extras[e])) for m in EXTRA_OF}
    assert {m: e for m, e in smallest.items() if EXTRA_OF[m] != e} == {"PIL": "heads"}
    assert EXTRA_OF["scipy"] == "au" and EXTRA_OF["DracoPy"] == "heads"


def test_require_names_the_extra_and_the_missing_module() -> None:
    assert require("json.decoder", "core").__name__ == "json.decoder"
    with pytest.raises(MissingExtraError, match=r"no_such_module_x.*pip install 'mien\[render\]'"):
        require("no_such_module_x", "render")
    with pytest.raises(MissingExtraError, match=r"pip install 'mien\[all\]'"):
        require("no_such_module_y")  # not in the table: the everything extra


def test_available_answers_without_raising() -> None:
    assert available("json") is True
    assert available("no_such_module_z") is False
