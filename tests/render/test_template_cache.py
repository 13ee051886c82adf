"""The sheet templates' compiled code kept between runs: the same sheet from a cold cache, a warm one
and none; a cache made with other environment settings, or one that cannot be written or read, is
not taken."""

from __future__ import annotations

from pathlib import Path

import jinja2

from patchgen.render import sheet
from patchgen.render.template_cache import bytecode_cache

from .test_sheet import _render

NAME = "patch-sheet.md.j2"


def _env(folder, **settings) -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.PackageLoader("patchgen.templates", "."),
                              bytecode_cache=bytecode_cache(str(folder)), **settings)


def _code(template: jinja2.Template):
    return template.root_render_func.__code__


def test_the_same_sheet_from_a_cold_cache_a_warm_one_and_none(tmp_path, monkeypatch):
    monkeypatch.setattr(sheet, "bytecode_cache", lambda: None)
    plain = _render()
    monkeypatch.setattr(sheet, "bytecode_cache", lambda: bytecode_cache(str(tmp_path)))
    assert _render() == plain  # compiled, and written to the cache
    assert len(list(tmp_path.glob("*.cache"))) == 2
    assert _render() == plain  # read from it


def test_code_compiled_with_other_settings_is_not_taken(tmp_path):
    trimmed = _env(tmp_path, trim_blocks=True).get_template(NAME)
    source = Path(trimmed.filename).read_text(encoding="utf-8")
    again = _env(tmp_path, trim_blocks=True)
    assert again.bytecode_cache.get_bucket(again, NAME, trimmed.filename, source).code is not None
    plain = _env(tmp_path)
    assert plain.bytecode_cache.get_bucket(plain, NAME, trimmed.filename, source).code is None


def test_a_cache_that_cannot_be_made_written_or_read_is_no_cache(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("")
    assert bytecode_cache(str(blocked / "templates")) is None
    folder = tmp_path / "cache"
    expected = _code(_env(tmp_path / "other").get_template(NAME))

    def refuse(*args, **kwargs):
        raise PermissionError("read-only")

    with monkeypatch.context() as m:
        m.setattr(jinja2.bccache.tempfile, "NamedTemporaryFile", refuse)
        assert _code(_env(folder).get_template(NAME)) == expected  # compiled, not written
    assert not list(folder.glob("*.cache"))
    _env(folder).get_template(NAME)  # written now
    [cached] = folder.glob("*.cache")
    cached.write_bytes(cached.read_bytes()[:40])  # cut short inside the source's checksum
    assert _code(_env(folder).get_template(NAME)) == expected  # compiled again
