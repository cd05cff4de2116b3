"""Print the method paper's procedure and ours side by side on the simulated Table 1 mechanical arm."""

import argparse

from bsp_ros.core.paper_comparison import compare_on_mechanical_arm, format_table

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--duration", type=float, default=120.0, help="session length (s)")
args = parser.parse_args()
rows, _ = compare_on_mechanical_arm(args.seed, args.duration)
print(f"Simulated Table 1 mechanical arm, {args.duration:g} s, force noise 0.05 N, markers 0.1 mm, seed {args.seed}")
print(format_table(rows))
