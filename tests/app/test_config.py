"""app/config.py: the settings object, read from the environment."""

from __future__ import annotations

import pytest

from app.config import DEFAULT_UPLOAD_LIMIT_MB, Settings, load_settings, upload_limit
from app.main import create_app


def test_the_default_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MESH_UPLOAD_LIMIT_MB", raising=False)
    assert Settings().upload_limit_mb == DEFAULT_UPLOAD_LIMIT_MB == 200
    assert upload_limit() == 200 * 1024 * 1024


@pytest.mark.parametrize(("text", "size"), [("0.5", 512 * 1024), (" 3 ", 3 << 20), ("", 200 << 20)])
def test_the_environment_sets_the_limit(
    monkeypatch: pytest.MonkeyPatch, text: str, size: int
) -> None:
    monkeypatch.setenv("MESH_UPLOAD_LIMIT_MB", text)
    assert load_settings().upload_limit == size
    assert create_app().state.upload_limit == size


@pytest.mark.parametrize("text", ["abc", "0", "-1", "nan", "inf"])
def test_a_bad_limit_is_one_clear_sentence(monkeypatch: pytest.MonkeyPatch, text: str) -> None:
    monkeypatch.setenv("MESH_UPLOAD_LIMIT_MB", text)
    with pytest.raises(
        ValueError, match=r"^MESH_UPLOAD_LIMIT_MB must be a positive number of megabytes"
    ):
        load_settings()


def test_create_app_takes_the_limit_in_bytes(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MESH_UPLOAD_LIMIT_MB", "abc")  # not read when the limit is given
    assert create_app(upload_limit=2000).state.upload_limit == 2000


@pytest.mark.parametrize(
    "text", ["normals.example.org", "ftp://x.example", "https://x.example/?a=1", "https://a b"]
)
def test_a_bad_public_url_is_one_clear_sentence(monkeypatch: pytest.MonkeyPatch, text: str) -> None:
    monkeypatch.setenv("MESH_PUBLIC_URL", text)
    with pytest.raises(ValueError, match=r"^MESH_PUBLIC_URL must be an http:// or https://"):
        load_settings()


def test_the_public_url_is_unset_by_default(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MESH_PUBLIC_URL", raising=False)
    assert load_settings().public_url is None
    monkeypatch.setenv("MESH_PUBLIC_URL", "https://normals.example.org/calc/")
    assert load_settings().public_url == "https://normals.example.org/calc/"


@pytest.mark.parametrize("text", ["docs.example.org", "ftp://x.example", "https://x.example/#a"])
def test_a_bad_docs_url_is_one_clear_sentence(monkeypatch: pytest.MonkeyPatch, text: str) -> None:
    monkeypatch.setenv("MESH_DOCS_URL", text)
    with pytest.raises(ValueError, match=r"^MESH_DOCS_URL must be") as raised:
        load_settings()
    assert str(raised.value) == (
        "MESH_DOCS_URL must be an http:// or https:// address without a query, such as "
        f"https://docs.normals.example.org/, not {text!r}."
    )


def test_the_docs_url_is_unset_by_default(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MESH_DOCS_URL", raising=False)
    assert load_settings().docs_url is None
    assert create_app().state.docs_url is None
    monkeypatch.setenv("MESH_DOCS_URL", "https://normals.example.org/docs/")
    assert load_settings().docs_url == "https://normals.example.org/docs/"
    assert create_app().state.docs_url == "https://normals.example.org/docs/"
