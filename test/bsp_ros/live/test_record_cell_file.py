"""Which cell file `bsp record` took its sensor mounting from: one line names it, metadata.yaml records it, and where
it is the shipped simulated cell's (the default), both say so plainly, as `bsp identify` does of such a bag: on a
real cell with no transform topic that mounting would be the simulator's rotation, taken for the cell's."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
from ros_domains import next_domain_id

from bsp_ros.bag import write_session_bag
from bsp_ros.bag.cell_metadata import (
    CELL_KEYS,
    SHIPPED_NOTE,
    cell_file_said,
    custom_data_from_cell,
    stated_from_custom_data,
)
from bsp_ros.bag.metadata import read_metadata
from bsp_ros.cell import SHIPPED_CELL, read_cell_file
from bsp_ros.cli import main
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.simulation import human_arm_cell, simulate_cell

ROOT = Path(__file__).resolve().parents[3]
PEER = Path(__file__).with_name("play_record_peer.py")


def test_the_shipped_cell_s_mounting_is_named_as_such_and_a_cell_of_ones_own_is_not(tmp_path: Path) -> None:
    shipped = read_cell_file()
    own = tmp_path / "my_cell.yaml"
    own.write_text(SHIPPED_CELL.read_text())  # the same mounting, in a cell file the user keeps
    mine = read_cell_file(own)
    assert cell_file_said(shipped) == f"cell file {SHIPPED_CELL}: {SHIPPED_NOTE}"
    assert cell_file_said(mine) == f"cell file {own}"
    remounted = replace(shipped, rotation_xyzw=(0.0, 0.0, 0.0, 1.0))  # the shipped file's name, another mounting
    shipped_flags = [custom_data_from_cell(c)[CELL_KEYS["shipped"]] for c in (shipped, mine, remounted)]
    assert shipped_flags == ["true", "false", "false"]
    stated, problem = stated_from_custom_data(custom_data_from_cell(mine))
    assert stated is not None and not problem and SHIPPED_NOTE not in stated.where and str(own) in stated.where


def test_identify_of_a_bag_with_the_shipped_cell_s_mounting_says_so(tmp_path: Path) -> None:
    # The simulated sensor is mounted as the shipped cell says: the bag identifies with that mounting, and says whose.
    session = simulate_cell(human_arm_cell(seed=4, duration_s=30.0)).session
    custom = custom_data_from_cell(read_cell_file())
    bag = write_session_bag(tmp_path / "bag", session, tf_static=False, custom_data=custom)
    out = tmp_path / "estimate.json"
    main(["identify", str(bag), "--json", str(out), "--format", "none"])
    document = json.loads(out.read_text())
    assert document["bag"]["rotation_source"] == "metadata"
    notes = [f.values["detail"] for f in findings_of(document["quality"]) if f.code is FindingCode.BAG_NOTE]
    (note,) = [n for n in notes if "the bag's metadata" in n]
    assert f"(cell file {SHIPPED_CELL} when recorded: {SHIPPED_NOTE})" in note, note


@pytest.mark.dds
def test_record_names_the_shipped_cell_file_once_and_writes_it_into_the_metadata(tmp_path: Path) -> None:
    from bsp_ros.live.runtime.ros import Client, message_class

    domain, out = next_domain_id(), tmp_path / "bag"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    command = [sys.executable, str(PEER), "record", "/ft_sensor/wrench", "--out", str(out), "--domain", str(domain)]
    recorder = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        with Client("wrench_publisher", domain) as client:
            publisher = client.publisher("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", "sensor_data")
            assert client.spin_until(lambda: publisher.get_subscription_count() > 0, 20.0), "record not discovered"
            wrench = message_class("geometry_msgs/msg/WrenchStamped")()
            wrench.header.frame_id = "ft_sensor"
            for _ in range(20):
                publisher.publish(wrench)
                client.spin(0.02)
            time.sleep(0.5)
        recorder.send_signal(signal.SIGINT)
        stdout, stderr = recorder.communicate(timeout=20)
    finally:
        if recorder.poll() is None:
            recorder.kill()
            recorder.communicate(timeout=10)
    assert recorder.returncode == 0, stderr
    (line,) = [x for x in stdout.splitlines() if x.startswith("cell: ")]
    assert line.startswith("cell: sensor ft_sensor in world, rotation xyzw [0.965926, 0.258819, 0.0, 0.0]"), line
    # The recorder runs from the source tree (PYTHONPATH), this test from wherever bsp_ros is installed: the
    # shipped file is the package's bsp_ros/config/cell.yaml in either.
    named = line.split(" from cell file ", 1)[1]
    assert named.endswith(f": {SHIPPED_NOTE}"), line
    _is_the_shipped_cell_file(Path(named.removesuffix(f": {SHIPPED_NOTE}")))
    custom = read_metadata(out / "metadata.yaml").custom
    assert custom[CELL_KEYS["shipped"]] == "true", custom
    _is_the_shipped_cell_file(Path(custom[CELL_KEYS["file"]]))


def _is_the_shipped_cell_file(path: Path) -> None:
    assert path.parts[-3:] == ("bsp_ros", "config", "cell.yaml"), path
    assert path.read_text() == SHIPPED_CELL.read_text(), path
