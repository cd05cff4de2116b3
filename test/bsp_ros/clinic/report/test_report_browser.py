"""The HTML report renders in a real headless browser (Debian chromium): not blank, plots visible, flags shown."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.cli import main

SUBJECT = "P007"  # as planted by the report_store fixture (conftest.py)
CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if os.access("/usr/bin/chromium", os.X_OK) else None)
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
]
BAND_RGB = np.array([214.7, 226.2, 239.0])  # the ±2 std band: #1f5fa6 at alpha 0.18 over white
FLAG_RGB = np.array([198.0, 40.0, 40.0])  # #c62828: flagged changes

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="needs chromium (apt-get install chromium; .ci/services.sh)")


def _chromium(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    assert CHROMIUM is not None
    env = {**os.environ, "HOME": str(tmp_path)}  # nothing of the browser's lands in the real home
    command = [CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, env=env, check=False)


@pytest.mark.slow
def test_report_renders_with_plots_and_flags(report_store: str, tmp_path: Path) -> None:
    from PIL import Image

    page = tmp_path / "report.html"
    assert main(["report", SUBJECT, "--out", str(page), "--store", report_store]) == 0
    shot = tmp_path / "shot.png"
    result = _chromium(tmp_path, f"--screenshot={shot}", "--window-size=1100,2600", page.as_uri())
    assert shot.exists(), f"chromium wrote no screenshot: {result.stderr[-2000:]}"
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.shape[:2] == (2600, 1100)
    not_white = (pixels < 245).any(axis=2).mean()
    assert 0.05 < not_white < 0.9, f"screenshot looks blank or broken: {not_white:.1%} non-white"
    assert pixels.std() > 20
    band = (np.abs(pixels - BAND_RGB) < 8).all(axis=2).sum()
    assert band > 20_000, f"no uncertainty bands visible ({band} px): the plots did not render"
    flagged = (np.abs(pixels - FLAG_RGB) < 30).all(axis=2).sum()
    assert flagged > 300, f"the planted change is not marked in red ({flagged} px)"

    dom = _chromium(tmp_path, "--dump-dom", page.as_uri()).stdout
    assert f'Arm parameters of subject <span id="subject">{SUBJECT}</span>' in dom
    sessions_table = dom.split('<table id="sessions">')[1].split("</table>")[0]
    assert sessions_table.count("<tr><td>") == 6  # one quality row per session
    assert "Elbow friction (passive moment) rose from" in dom and "NOT VALID" in dom
    assert dom.count("data:image/png;base64,") == 18
