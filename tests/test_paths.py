import pytest

from mien import InvalidValueError, MissingAssetError, UnknownNameError
from mien.paths import asset_path, require_asset


def test_asset_path_order_explicit_env_config(tmp_path, monkeypatch):
    config = tmp_path / "config.toml"
    config.write_text('[assets]\nface_landmarker = "/from/config.task"\n')
    monkeypatch.setenv("MIEN_CONFIG", str(config))
    monkeypatch.delenv("MIEN_FACE_LANDMARKER", raising=False)
    assert str(asset_path("face_landmarker")) == "/from/config.task"
    monkeypatch.setenv("MIEN_FACE_LANDMARKER", "/from/env.task")
    assert str(asset_path("face_landmarker")) == "/from/env.task"
    assert str(asset_path("face_landmarker", "/explicit.task")) == "/explicit.task"


def test_missing_asset_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "none.toml"))
    monkeypatch.delenv("MIEN_ICT_FACEKIT", raising=False)
    with pytest.raises(MissingAssetError, match="MIEN_ICT_FACEKIT"):
        require_asset("ict_facekit")
    with pytest.raises(MissingAssetError, match="not found at"):
        require_asset("ict_facekit", tmp_path / "nowhere")
    with pytest.raises(UnknownNameError):
        asset_path("teapot")


def test_malformed_config_is_a_clear_error(tmp_path, monkeypatch):
    config = tmp_path / "config.toml"
    config.write_text("[assets\nbroken = ")
    monkeypatch.setenv("MIEN_CONFIG", str(config))
    monkeypatch.delenv("MIEN_EMOTION_MODEL", raising=False)
    with pytest.raises(InvalidValueError, match="config file"):
        asset_path("emotion_model")
