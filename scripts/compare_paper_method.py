"""Print the method paper's procedure and ours side by side on the simulated Table 1 mechanical arm."""

import argparse

from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.paper import identify_paper
from bsp_ros.core.paper_comparison import compare_on_mechanical_arm, format_table

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--duration", type=float, default=120.0, help="session length (s)")
args = parser.parse_args()
rows, session = compare_on_mechanical_arm(args.seed, args.duration)
print(f"Simulated Table 1 mechanical arm, {args.duration:g} s, force noise 0.05 N, markers 0.1 mm, seed {args.seed}")
print(format_table(rows))
# The split of the unidentifiable group m1 l1 + a1 m2 that the paper's bounded solver happens to return.
split = identify_paper(identification_data_from_session(session.session)).diagnostics["paper_pi"]
assert isinstance(split, dict)
m1_l1, m2 = split["m1l1"], split["m2"]
print(f"paper method's split of m1 l1 + a1 m2 (not identifiable): m1 l1 = {m1_l1:.3g} kgm, m2 = {m2:.3g} kg")
