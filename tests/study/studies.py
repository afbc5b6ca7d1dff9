"""A small study made once per test module, and a TestClient on it over a database of the test's own."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mien.study.design import load_design
from mien.study.runner import create_app
from mien.study.stimuli import make_stimuli
from mien.study.storage import Store, database_url


def make_study(folder: Path, design_text: str) -> tuple[Any, dict[str, Any], Path]:
    """(design, manifest, stimuli folder) of the design ``design_text`` written into ``folder``, stimuli made."""
    path = folder / "design.toml"
    path.write_text(design_text)
    design = load_design(path)
    result = make_stimuli(design, progress=False)
    return design, result.manifest, result.manifest_path.parent


def client_for(study: tuple, db: Path, **store_options: float):  # type: ignore[no-untyped-def]
    """(TestClient, Store) of ``study`` answering into the SQLite file ``db``."""
    from fastapi.testclient import TestClient

    design, manifest, folder = study
    store = Store(database_url(db, db), **store_options)
    store.register_stimuli(design.name, design.protocol, manifest["stimuli"])
    return TestClient(create_app(design, manifest, folder, store)), store
