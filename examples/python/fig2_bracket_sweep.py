#!/usr/bin/env python3
"""Fig. 2 of the information-form paper, small: one Info-NLP schedule of a reference plant
(n = 5, M = 30, P0 = 100 I, Q = I) kept fixed while every R_j is scaled by R_scale in
[1e-2, 1e2]; for each scale, the two surrogate costs against the Monte Carlo estimate of E[J(P)].

    PYTHONPATH=build/python python3 examples/python/fig2_bracket_sweep.py          # 9 scales
    PYTHONPATH=build/python python3 examples/python/fig2_bracket_sweep.py --full   # 25 scales, 2000 runs

Prints the signed deviations (J(P_info) - MC) / MC and (J(P_cov) - MC) / MC per scale, writes them
to fig2.csv, and checks Corollary 1 at every scale: J(P_info) <= E[J] <= J(P_cov) within the
Monte Carlo's 95% interval.
"""

import argparse
import csv

import numpy as np

import sensornet


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true", help="25 scales and 2000 runs each")
    parser.add_argument("--out", default="fig2.csv", help="the table of every scale")
    args = parser.parse_args()
    scales = np.logspace(-2, 2, 25 if args.full else 9)
    runs = 2000 if args.full else 1000

    reference = sensornet.random_scenario(states=5, sensors=30, seed=1, budget=5.0)
    schedule = sensornet.plan(reference, surrogate="info").rates
    rows, failures = [], []
    print(f"{'R_scale':>9} {'MC E[J]':>11} {'+-95%':>9} {'info dev':>9} {'cov dev':>9}")
    for scale in scales:
        s = sensornet.random_scenario(states=5, sensors=30, seed=1, budget=5.0, noise_scale=scale)
        b = sensornet.bracket(s, schedule)
        e = sensornet.evaluate(s, schedule, runs=runs, seed=1, plant=False)
        info_dev, cov_dev = (b.info - e.mean) / e.mean, (b.cov - e.mean) / e.mean
        print(f"{scale:9.3g} {e.mean:11.5g} {e.ci95:9.2g} {info_dev:+9.3f} {cov_dev:+9.3f}")
        rows.append({"r_scale": scale, "mc_mean": e.mean, "mc_ci95": e.ci95, "mc_std": e.std_dev,
                     "info": b.info, "cov": b.cov, "info_deviation": info_dev,
                     "cov_deviation": cov_dev})
        if not b.contains(e.mean, slack=e.ci95):
            failures.append(f"R_scale {scale:.3g}: {e.mean} +- {e.ci95} outside {b}")
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out} ({len(rows)} scales)")
    for line in failures:
        print("FAILED:", line)
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
