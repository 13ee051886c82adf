"""Writing a command's output files all or nothing, never replacing a file without being told."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from .errors import InputError


def write_files(out_dir: str | Path, files: dict[str, str | bytes], force: bool = False,
                option: str = "-o") -> list[Path]:
    """Write every file into out_dir, or none: files are staged in a temporary directory beside
    out_dir and moved in only when all are ready. Existing files are replaced only with force."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(str(out), option, "exists and is not a directory")
    clash = [n for n in files if (out / n).exists()]
    if clash and not force:
        raise InputError(str(out / clash[0]), option,
                         f"already exists ({len(clash)} output file(s) would be replaced); use --force to replace")
    out.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=".patchgen-", dir=out.parent))
    try:
        for name, data in files.items():
            p = stage / name
            p.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(data, bytes):
                p.write_bytes(data)
            else:
                p.write_text(data, encoding="utf-8")
        out.mkdir(parents=True, exist_ok=True)
        written = []
        for name in files:
            (out / name).parent.mkdir(parents=True, exist_ok=True)
            os.replace(stage / name, out / name)
            written.append(out / name)
        return written
    finally:
        shutil.rmtree(stage, ignore_errors=True)
