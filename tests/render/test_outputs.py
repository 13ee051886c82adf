"""The all-or-nothing writer on its own: what it writes, what it refuses, and that a refusal or a
failure half-way leaves the output folder as it was."""

from __future__ import annotations

from pathlib import Path

import pytest

from patchgen.inputs.errors import InputError
from patchgen.render.outputs import NAME_MAX, check_out_dir, write_files

FILES = {"netlist.json": '{"a": 1}\n', "pots.csv": "pot,setting\nP1,0.500\n", "plots/step.png": b"\x89PNG\x00\xff"}


def _tree(folder: Path) -> dict[str, bytes]:
    """Every file under a folder (hidden ones too), by relative path."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _want(files: dict[str, str | bytes]) -> dict[str, bytes]:
    return {k: v if isinstance(v, bytes) else v.encode() for k, v in sorted(files.items())}


def test_writes_every_file_into_a_new_folder(tmp_path):
    out = tmp_path / "new" / "deeper"
    written = write_files(out, FILES)
    assert written == [out / name for name in FILES]
    assert _tree(out) == _want(FILES)  # text as UTF-8, bytes untouched, nothing staged left over
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new"]


def test_an_existing_file_is_replaced_only_with_force(tmp_path):
    (tmp_path / "pots.csv").write_text("old")
    (tmp_path / "keep.txt").write_text("mine")
    with pytest.raises(InputError) as exc:
        write_files(tmp_path, FILES)
    assert "already exists (1 output file(s) would be replaced); use --force" in exc.value.message
    assert _tree(tmp_path) == {"keep.txt": b"mine", "pots.csv": b"old"}  # nothing written
    write_files(tmp_path, FILES, force=True)
    assert _tree(tmp_path) == _want({**FILES, "keep.txt": "mine"})


def test_a_bad_json_file_stops_every_file(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="NaN in a JSON output file"):
        write_files(out, {"pots.csv": "x\n", "design.json": '{"pm": NaN}'})
    assert not out.exists()
    with pytest.raises(ValueError, match="Infinity"):
        write_files(tmp_path, {"a.json": "[Infinity]"})
    assert _tree(tmp_path) == {}


def test_a_failure_half_way_writes_nothing(tmp_path, monkeypatch):
    (tmp_path / "netlist.json").write_text("old")
    real = Path.write_bytes

    def full_disk(self, data):
        if self.name == "step.png":
            raise OSError(28, "No space left on device")
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", full_disk)
    with pytest.raises(InputError) as exc:
        write_files(tmp_path, FILES, force=True)
    assert exc.value.message == "cannot be written (no space left on the device)"
    assert _tree(tmp_path) == {"netlist.json": b"old"}  # the old file kept, no staging folder left


def test_a_directory_in_the_way_is_refused_even_with_force(tmp_path):
    (tmp_path / "pots.csv").mkdir()
    with pytest.raises(InputError, match="is a directory where an output file goes"):
        write_files(tmp_path, FILES, force=True)
    (tmp_path / "pots.csv").rmdir()
    (tmp_path / "plots").write_text("a file")
    with pytest.raises(InputError, match="is a file where the output folder plots goes"):
        write_files(tmp_path, FILES, force=True)
    assert _tree(tmp_path) == {"plots": b"a file"}


@pytest.mark.parametrize(("folder", "says"), [
    ("", "empty: name an output folder"),
    ("  ", "empty: name an output folder"),
    ("a\0b", "cannot contain a NUL character"),
    ("/proc/patchgen", "is under /proc, a kernel file system"),
    ("/dev", "is under /dev, a kernel file system"),
    ("x" * (NAME_MAX + 1), f"longer than the file system allows ({NAME_MAX} bytes)"),
])
def test_unusable_folders_are_refused(folder, says):
    with pytest.raises(InputError) as exc:
        check_out_dir(folder)
    assert exc.value.field == "-o" and says in exc.value.message


def test_a_file_as_the_folder_or_on_its_way_is_refused(tmp_path):
    f = tmp_path / "a-file"
    f.write_text("")
    with pytest.raises(InputError, match="exists and is not a directory"):
        check_out_dir(f)
    with pytest.raises(InputError, match="is a file, not a folder"):
        check_out_dir(f / "below" / "out", option="--out")
    assert check_out_dir(tmp_path / "fresh", ["x.csv"]) == tmp_path / "fresh"
    assert not (tmp_path / "fresh").exists()  # the check creates nothing


def test_a_long_text_is_written_whole_across_its_chunks(tmp_path):
    # 2.8 million characters, two bytes each for the accents: written a million characters at a
    # time, the file is the text's UTF-8 encoding exactly
    text = "é, 1.25e-05 -0 é\n" * 165_000
    write_files(tmp_path / "o", {"big.txt": text, "small.txt": "x\n"})
    assert (tmp_path / "o" / "big.txt").read_bytes() == text.encode("utf-8")
    assert (tmp_path / "o" / "small.txt").read_bytes() == b"x\n"
