"""The report's first page, rendered by headless Chromium (HTML, and HTML printed) and from the PDF (pdftoppm).

The F1 history (clinic_history): elbow friction falls 0.80 -> 0.40 Nm in two planted steps, one session in
between is not usable and claims 5 Nm. The first page must name exactly that change, in plain words.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from html import unescape
from pathlib import Path

import numpy as np
import pytest
from clinic_history import FRICTION, INVALID_VALUE_NM, History
from report_histories import CURVES, build_curves

from bsp_ros.cli import main
from bsp_ros.clinic.report import analyse
from bsp_ros.clinic.report.curve_views import CURVES_TITLE
from bsp_ros.clinic.report.labels import plain_name
from bsp_ros.clinic.store import open_store

CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if os.access("/usr/bin/chromium", os.X_OK) else None)
POPPLER = all(shutil.which(tool) for tool in ("pdftoppm", "pdftotext", "pdfinfo"))
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--no-pdf-header-footer",
]
RAW_KEY = re.compile(r"\b(joints|segments|quality)\.\w+|\b\w+_(nm|kgm|kg|m|rad|nms|per_rad)\b|weight_support|CONTRACT")
EXPONENT = re.compile(r"\d(\.\d+)?[eE][+-]?\d")
FLAG_RGB = np.array([198.0, 40.0, 40.0])  # #c62828, the flagged step
A4_PT = (595.0, 842.0)
FRICTION_NAME = plain_name(("joints", "elbow", "coulomb_nm"))


def _run(*command: str) -> str:
    result = subprocess.run(list(command), capture_output=True, text=True, timeout=180, check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    return result.stdout


def _chromium(tmp_path: Path, *args: str) -> str:
    assert CHROMIUM is not None
    env = {**os.environ, "HOME": str(tmp_path)}  # nothing of the browser's lands in the real home
    command = [CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=180, env=env, check=False).stdout


def _text(html: str) -> str:
    return " ".join(unescape(re.sub(r"<[^>]+>", " ", html)).split())


def _pdf_page_text(pdf: Path, page: int) -> str:
    return " ".join(_run("pdftotext", "-layout", "-f", str(page), "-l", str(page), str(pdf), "-").split())


def _pages(pdf: Path) -> list[tuple[float, float]]:
    info = _run("pdfinfo", "-f", "1", "-l", "99", str(pdf))
    return [(float(w), float(h)) for w, h in re.findall(r"Page\s+\d+ size:\s+([\d.]+) x ([\d.]+) pts", info)]


PEERS_HEADING = "Arm weight against its peers"


def _peers_page(pdf: Path) -> int:
    """The page the peers section starts on (its heading and the de Leva tables' source after it on that page or
    the next)."""
    pages = [_pdf_page_text(pdf, page) for page in range(1, len(_pages(pdf)) + 1)]
    (start,) = [k for k, text in enumerate(pages, start=1) if PEERS_HEADING in text]
    after = pages[start - 1].split(PEERS_HEADING, 1)[1] + " ".join(pages[start : start + 1])
    assert "de Leva (1996)" in after
    return start


def _names_in(text: str, history: History) -> set[str]:
    with open_store(history.store) as store:
        analysis = analyse(FRICTION, store.sessions(FRICTION), pool=store.sessions())
    return {plain_name(s.key) for s in analysis.series if plain_name(s.key).lower() in text.lower()}


def _check_first_page(text: str, history: History) -> None:
    assert "Arm assessment" in text and FRICTION in text and "female, 68 kg" in text
    headline = text.split("Measurement error (MDC95) from")[0]
    changed = headline.split("No change beyond measurement error")[0]  # the red sentences come first
    assert _names_in(changed, history) == {FRICTION_NAME}, headline
    assert "elbow stiffness" in headline.split("No change beyond measurement error")[1]
    assert re.search(r"Resistance to passive elbow movement \(friction\) fell 5\d %", headline), headline
    assert "Not usable:" in text and "Detail: every parameter" not in text
    assert not RAW_KEY.search(text), RAW_KEY.search(text)
    assert not EXPONENT.search(text), EXPONENT.search(text)


def _red_pixels(png: Path) -> int:
    from PIL import Image

    pixels = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    assert 0.03 < (pixels < 245).any(axis=2).mean() < 0.9, "the page looks blank or broken"
    return int((np.abs(pixels - FLAG_RGB) < 30).all(axis=2).sum())


@pytest.fixture(scope="module")
def written(history: History, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("report")
    html, pdf = out / "report.html", out / "report.pdf"
    assert main(["report", FRICTION, "--out", str(html), "--pdf", str(pdf), "--store", str(history.store)]) == 0
    return {"html": html, "pdf": pdf, "dir": out}


@pytest.mark.skipif(CHROMIUM is None or not POPPLER, reason="needs chromium and poppler-utils (.ci/services.sh)")
def test_html_first_page_in_chromium_and_printed(written: dict[str, Path], history: History, tmp_path: Path) -> None:
    dom = _chromium(tmp_path, "--dump-dom", written["html"].as_uri())
    first = dom.split('<section id="first-page">')[1].split("</section>")[0]
    _check_first_page(_text(first), history)
    shot = tmp_path / "shot.png"
    _chromium(tmp_path, f"--screenshot={shot}", "--window-size=900,1300", written["html"].as_uri())
    assert _red_pixels(shot) > 200, "the planted change is not marked in red"
    printed = tmp_path / "printed.pdf"
    _chromium(tmp_path, f"--print-to-pdf={printed}", written["html"].as_uri())
    sizes = _pages(printed)
    assert len(sizes) >= 2 and all(abs(w - A4_PT[0]) < 2 and abs(h - A4_PT[1]) < 2 for w, h in sizes)
    page1 = _pdf_page_text(printed, 1)
    _check_first_page(page1, history)
    assert f"Page 1 of {len(sizes)}" in page1 and "made 20" in page1
    assert _pdf_page_text(printed, 2).startswith("Detail: every parameter")
    # The detail names the documents that explain it, which a clone of the repository has (test_docs.py).
    last = _pdf_page_text(printed, len(sizes))
    assert "docs/clinic.md" in last and "docs/method.md" in last


@pytest.mark.skipif(not POPPLER, reason="needs poppler-utils (pdftoppm, pdftotext, pdfinfo; .ci/services.sh)")
def test_pdf_is_a4_with_a_standalone_first_page(written: dict[str, Path], history: History, tmp_path: Path) -> None:
    pdf = written["pdf"]
    sizes = _pages(pdf)
    assert len(sizes) >= 2 and all(abs(w - A4_PT[0]) < 2 and abs(h - A4_PT[1]) < 2 for w, h in sizes)
    _check_first_page(_pdf_page_text(pdf, 1), history)
    assert "Detail: every parameter" in _pdf_page_text(pdf, 2)
    for page in range(1, len(sizes) + 1):
        text = _pdf_page_text(pdf, page)
        assert f"Page {page} of {len(sizes)}" in text and "made 20" in text and FRICTION in text
    assert "docs/clinic.md" in _pdf_page_text(pdf, len(sizes)) and "docs/clinic.md" not in _pdf_page_text(pdf, 1)
    assert _peers_page(pdf) in (1, 2)
    _run("pdftoppm", "-png", "-r", "60", "-f", "1", "-l", "1", str(pdf), str(tmp_path / "page"))
    (png,) = tmp_path.glob("page*.png")
    assert _red_pixels(png) > 100, "the planted change is not marked in red on the first page"


@pytest.mark.skipif(not POPPLER, reason="needs poppler-utils (pdftotext, pdfinfo; .ci/services.sh)")
def test_the_peers_stand_on_page_1_or_2_after_the_passive_curves(tmp_path: Path) -> None:
    store = build_curves(tmp_path / "clinic.sqlite")
    pdf = tmp_path / "report.pdf"
    assert main(["report", CURVES, "--pdf", str(pdf), "--store", str(store)]) == 0
    assert CURVES_TITLE in _pdf_page_text(pdf, 2)  # the curves of three joints come first in the detail
    assert _peers_page(pdf) in (1, 2)


def test_an_invalid_session_is_a_marked_gap_not_a_value(history: History) -> None:
    from matplotlib.figure import Figure

    from bsp_ros.clinic.report.plots import draw_panel

    with open_store(history.store) as store:
        analysis = analyse(FRICTION, store.sessions(FRICTION), pool=store.sessions())
    panel = [s for s in analysis.series if s.key == ("joints", "elbow", "coulomb_nm")]
    axes = Figure().add_subplot()
    draw_panel(axes, panel, ["left"])
    drawn = np.concatenate([np.asarray(line.get_ydata(), dtype=float) for line in axes.get_lines()])
    assert INVALID_VALUE_NM not in drawn[np.isfinite(drawn)].tolist()
    assert axes.get_ylim()[1] < 1.0  # the 5 Nm claim does not stretch the axis
    assert any(t.get_text() == "not usable" for t in axes.texts)
