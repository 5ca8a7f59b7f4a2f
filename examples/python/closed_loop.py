#!/usr/bin/env python3
"""The closed loop against the open-loop plan: a plan made once before the episode, and the same
plan with the rest of every episode re-planned every DT emulated seconds from the filter's
covariance (`sensornet launch --replan-every DT`), on the same arrivals, so that the difference
is paired episode by episode.

    PYTHONPATH=build/python python3 examples/python/closed_loop.py [--scenario FILE] [--runs N]

Prints, per DT, the closed loop's mean cost, the open loop's on the same arrivals, and their
paired difference with its 95% interval ("feedback pays" when the interval is below 0). The
filter's covariance depends on when measurements arrived, not on their values: the difference
is what reacting to the arrivals that happened is worth.
"""

import argparse
import pathlib

import sensornet

HERE = pathlib.Path(__file__).resolve().parent


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=HERE.parents[1] / "scenarios" / "default.yaml")
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--every", type=float, nargs="+", default=[1.0, 0.5])
    args = parser.parse_args()
    s = sensornet.load_scenario(args.scenario)
    p = sensornet.plan(s, surrogate="info")
    print(f"open-loop info plan: bracket [{p.bracket.info:.5g}, {p.bracket.cov:.5g}], {p.status}")
    print(f"{'DT':>5} {'closed':>10} {'open':>10} {'closed - open':>14} {'+-95%':>9}  verdict")
    for every in args.every:
        c = sensornet.closed_loop(s, p, replan_every=every, surrogate="info", runs=args.runs, seed=1)
        g = c.gain
        verdict = ("feedback pays" if g["mean"] + g["ci95"] < 0 else
                   "feedback costs" if g["mean"] - g["ci95"] > 0 else "no difference at this size")
        print(f"{every:5.2g} {c.mean:10.5g} {c.open_mean:10.5g} {g['mean']:+14.4g} {g['ci95']:9.2g}  {verdict}")
        if c.runs != args.runs or len(c.episode_costs) != args.runs:
            print("FAILED: not every episode was run")
            return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
