"""The sheets patchgen writes (with their bench prediction) print on at most two pages."""

import shutil
import subprocess
import sys

import pytest

from tests.conftest import ROOT

from .test_sheet import MM, _pdf_pages

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def print_pages(html, tmp_path):
    pdf = tmp_path / "sheet.pdf"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    f"--user-data-dir={tmp_path / 'profile'}", "--no-pdf-header-footer", f"--print-to-pdf={pdf}",
                    html.as_uri()], check=True, capture_output=True, timeout=180)
    return _pdf_pages(pdf.read_bytes())


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
@pytest.mark.parametrize("args", [
    ["patch", "thesis-ch5", "--runs", "4"],
    ["patch", "bench-recommended", "--runs", "4"],
    ["swingup", "bench-recommended"],
])
def test_written_sheet_fits_two_pages(tmp_path, args):
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "patchgen", *args, "-o", str(out)], capture_output=True, text=True,
                       cwd=ROOT)
    assert r.returncode == 0, r.stderr
    pages, boxes = print_pages(out / "patch-sheet.html", tmp_path)
    assert 1 <= pages <= 2
    assert all(w <= 210 * MM + 0.5 and h <= 279.4 * MM + 0.5 for w, h in boxes)
    assert "Predicted on the bench" in (out / "patch-sheet.html").read_text()
