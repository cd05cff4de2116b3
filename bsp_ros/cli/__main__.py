"""`python -m bsp_ros.cli` runs the `bsp` command line."""

import sys

from bsp_ros.cli import main

sys.exit(main())
