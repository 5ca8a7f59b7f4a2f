#!/usr/bin/env python3
"""Fig. 1 of the information-form paper, small: Info-NLP and Cov-NLP against the uniform schedule
over random plants (n = 5 states, M sensors), with their solve times and the Monte Carlo
estimate of the realized cost E[J(P)] of each returned schedule.

    PYTHONPATH=build/python python3 examples/python/fig1_planners_vs_uniform.py          # small
    PYTHONPATH=build/python python3 examples/python/fig1_planners_vs_uniform.py --full   # the paper's sweep

Prints one row per (M, planner): the median solve time and the median and interquartile range
of the Monte Carlo cost over the instances, and writes every cell to fig1.csv. It checks what
the paper shows: each plan's Monte Carlo cost lies in its own bracket (Corollary 1, within the
95% interval), and both planners beat uniform on the median.
"""

import argparse
import csv
import statistics

import sensornet


def quartiles(values):
    q = statistics.quantiles(values, n=4, method="inclusive") if len(values) > 1 else values * 3
    return q[0], q[1], q[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true",
                        help="the paper's sweep: M = 30..100 by 10, 10 instances, 100 runs")
    parser.add_argument("--out", default="fig1.csv", help="the table of every cell")
    args = parser.parse_args()
    sensors = range(30, 101, 10) if args.full else (10, 20, 30)
    instances = 10 if args.full else 5
    runs = 100 if args.full else 500

    rows, failures = [], []
    for m in sensors:
        for seed in range(1, instances + 1):
            s = sensornet.random_scenario(states=5, sensors=m, seed=seed, budget=5.0)
            for planner in ("info", "cov", "uniform"):
                p = sensornet.plan(s, surrogate=planner)
                e = sensornet.evaluate(s, p, runs=runs, seed=seed, plant=False)
                if not p.bracket.contains(e.mean, slack=e.ci95):
                    failures.append(f"M={m} seed={seed} {planner}: {e.mean} outside {p.bracket}")
                rows.append({"sensors": m, "seed": seed, "planner": planner,
                             "solve_seconds": p.solve_seconds, "status": p.status,
                             "mc_mean": e.mean, "mc_ci95": e.ci95,
                             "bracket_info": p.bracket.info, "bracket_cov": p.bracket.cov})
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)

    print(f"{'M':>4} {'planner':8} {'time s':>8} {'E[J] median':>12} {'IQR':>22}")
    medians = {}
    for m in sensors:
        for planner in ("info", "cov", "uniform"):
            cell = [r for r in rows if r["sensors"] == m and r["planner"] == planner]
            time_s = statistics.median(r["solve_seconds"] for r in cell)
            q1, q2, q3 = quartiles([r["mc_mean"] for r in cell])
            medians[m, planner] = q2
            print(f"{m:>4} {planner:8} {time_s:8.3f} {q2:12.5g} [{q1:9.5g}, {q3:9.5g}]")
    print(f"wrote {args.out} ({len(rows)} cells)")
    for m in sensors:
        for planner in ("info", "cov"):
            if medians[m, planner] >= medians[m, "uniform"]:
                failures.append(f"M={m}: {planner}'s median cost does not beat uniform's")
    for line in failures:
        print("FAILED:", line)
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
