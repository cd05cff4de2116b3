"""Writer for the kill test: adds sessions in a loop and prints an ack line after each commit.

Usage: python kill_writer.py DB FIRST_INDEX
"""

from __future__ import annotations

import sys

from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate


def main() -> None:
    """Add sessions ``FIRST_INDEX, FIRST_INDEX + 1, ...`` until killed."""
    path, index = sys.argv[1], int(sys.argv[2])
    store = open_store(path)
    print("open", flush=True)
    while True:
        subject = f"K{index % 5}"
        time_ns = SAMPLE_START_NS + index * 10**9
        store.add_estimate(sample_estimate(index, start_time_ns=time_ns), subject)
        sys.stdout.write(f"ack {subject} {time_ns}\n")  # only after add() returned: committed
        sys.stdout.flush()
        index += 1


if __name__ == "__main__":
    main()
