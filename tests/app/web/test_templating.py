"""The compiled-template cache: used while a template is unchanged, never in the way."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from jinja2 import Environment, FileSystemLoader

from app.web import templating
from app.web.templating import TEMPLATES_DIR, TemplateCache, compile_templates


def environment(folder: Path, cache: Path) -> Environment:
    return Environment(
        loader=FileSystemLoader(folder), bytecode_cache=TemplateCache(str(cache), "%s.cache")
    )


def test_compile_templates_fills_the_cache_with_every_page() -> None:
    pages = sorted(path.name for path in TEMPLATES_DIR.glob("*.html"))
    assert compile_templates() == len(pages) > 10
    entries = list(templating.CACHE_DIR.glob("*.cache"))
    assert len(entries) >= len(pages)


def test_a_cached_template_is_read_back_and_a_changed_one_recompiled(tmp_path: Path) -> None:
    folder, cache = tmp_path / "templates", tmp_path / "templates" / "__pycache__"
    folder.mkdir()
    (folder / "page.html").write_text("one {{ x }}")
    assert environment(folder, cache).get_template("page.html").render(x=1) == "one 1"
    assert len(list(cache.glob("*.cache"))) == 1  # the folder is made on the first write
    # A new environment (a new server) reads the entry: its code, not a new compilation.
    fresh = environment(folder, cache)
    compiled: list[str] = []
    original = fresh.compile
    fresh.compile = lambda *args, **kwargs: compiled.append("x") or original(*args, **kwargs)  # type: ignore[method-assign]
    assert fresh.get_template("page.html").render(x=2) == "one 2"
    assert compiled == []
    # The source changes: the checksum differs, so the entry is not used.
    (folder / "page.html").write_text("two {{ x }}")
    assert environment(folder, cache).get_template("page.html").render(x=3) == "two 3"


@pytest.mark.parametrize("garbage", [b"", b"j2\x00", os.urandom(64), b"j2" + os.urandom(200)])
def test_a_broken_entry_is_compiled_again(tmp_path: Path, garbage: bytes) -> None:
    folder, cache = tmp_path / "t", tmp_path / "c"
    folder.mkdir()
    (folder / "page.html").write_text("{{ 6 * 7 }}")
    environment(folder, cache).get_template("page.html")
    (entry,) = cache.glob("*.cache")
    entry.write_bytes(garbage)
    assert environment(folder, cache).get_template("page.html").render() == "42"


def test_a_cache_that_cannot_be_written_or_read_is_done_without(tmp_path: Path) -> None:
    folder = tmp_path / "t"
    folder.mkdir()
    (folder / "page.html").write_text("{{ 'ok' }}")
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    assert environment(folder, blocker / "cache").get_template("page.html").render() == "ok"
    assert not (blocker / "cache").exists()
    cache = tmp_path / "c"
    environment(folder, cache).get_template("page.html")
    (entry,) = cache.glob("*.cache")
    entry.unlink()
    entry.mkdir()  # reading it fails with IsADirectoryError
    assert environment(folder, cache).get_template("page.html").render() == "ok"
