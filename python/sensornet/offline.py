"""sensornet's math without a run: scenarios, plans, brackets, Monte Carlo, the closed loop, the
surrogates' trajectories and the exact CD-KF, numpy arrays in and out.

Every function calls what the programs call, with their defaults, so the numbers are theirs for
the same inputs: plan() is `coordinator plan`, evaluate() and closed_loop() are `fusion_center
evaluate` (the same seed gives the same mean, bit for bit, for any thread count).

    import sensornet
    s = sensornet.random_scenario(states=5, sensors=30, seed=3, budget=5.0)
    p = sensornet.plan(s, surrogate="info")            # p.rates: N x M, p.bracket.info/.cov
    e = sensornet.evaluate(s, p, runs=2000, seed=7)     # e.mean +- e.ci95
    assert p.bracket.info <= e.mean + e.ci95 and e.mean - e.ci95 <= p.bracket.cov
    t, P = sensornet.trajectory(s, p, form="cov", times=np.linspace(0, s.horizon, 61))

A schedule argument is an N x M array of rates (Hz), a Plan, or the path of a schedule file.
Bad input raises sensornet.InputError (a ValueError) with the programs' one-line text.
"""

import dataclasses
import os
import pathlib

import numpy as np

from . import _sensornet as _m
from ._sensornet import InputError, Scenario

__all__ = ["InputError", "Scenario", "Bracket", "Plan", "Evaluation", "ClosedLoop", "Filtered",
           "load_scenario", "parse_scenario", "random_scenario", "uniform", "load_schedule",
           "write_schedule", "plan", "bracket", "evaluate", "closed_loop", "trajectory", "cdkf"]


@dataclasses.dataclass(frozen=True)
class Bracket:
    """Corollary 1 of the first paper: info = J(P_info) <= E[J(P)] <= J(P_cov) = cov."""
    info: float
    cov: float

    def contains(self, value, slack=0.0):
        return self.info - slack <= value <= self.cov + slack


@dataclasses.dataclass(frozen=True)
class Plan:
    """A planned schedule (`coordinator plan`): rates is N x M (Hz), bracket its Corollary 1."""
    rates: np.ndarray
    surrogate: str
    status: str
    solved: bool
    objective: float
    objective_half_width: float
    bracket: Bracket
    iterations: int
    substeps: int
    kkt_residual: float
    solve_seconds: float
    episodes: int


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """The Monte Carlo of `fusion_center evaluate`: the realized cost J(P) over `runs` episodes,
    its mean with the 95% half-width ci95, and every episode's cost in episode order."""
    runs: int
    mean: float
    std_dev: float
    ci95: float
    nees_mean: float
    squared_error_mean: float
    arrivals_mean: float
    episode_costs: np.ndarray
    timetable: "Evaluation | None" = None
    seconds: float = 0.0

    @property
    def interval(self):
        return (self.mean - self.ci95, self.mean + self.ci95)


@dataclasses.dataclass(frozen=True)
class ClosedLoop:
    """The closed loop of `fusion_center evaluate --replan-every`, and the open-loop plan on the
    same arrivals: gain is closed minus open, paired episode by episode (mean, std_dev, ci95)."""
    runs: int
    mean: float
    std_dev: float
    ci95: float
    open_mean: float
    gain: dict
    tails_mean: float
    refused: int
    arrivals_mean: float
    episode_costs: np.ndarray
    seconds: float


@dataclasses.dataclass(frozen=True)
class Filtered:
    """The exact CD-KF over given measurement instants: J(P) of eq. (6) and P(T)."""
    cost: float
    running_cost: float
    terminal_cost: float
    covariance: np.ndarray


def load_scenario(path):
    """A scenario file (YAML, explicit or random-plant form), validated."""
    return _m.load_scenario(os.fspath(path))


def parse_scenario(text, source="scenario"):
    """A scenario from YAML text; `source` names it in errors."""
    return _m.parse_scenario(text, source)


def random_scenario(states=5, sensors=30, seed=1, noise_scale=1.0, budget=5.0, horizon=3.0,
                    intervals=30, rows_per_sensor=1, energy=None):
    """The first paper's random plant (Section V-A), as a scenario file's `random:` form makes it;
    `energy` gives every sensor the budget ∫λ_j dt <= energy (expected measurements)."""
    return _m.random_scenario(int(states), int(sensors), int(seed), float(noise_scale),
                              float(budget), float(horizon), int(intervals), int(rows_per_sensor),
                              float("inf") if energy is None else float(energy))


def _budgeted(scenario, budget):
    return scenario if budget is None else scenario.with_budget(float(budget))


def _rates(scenario, schedule):
    if schedule is None:
        return _m.uniform_rates(scenario)
    if isinstance(schedule, Plan):
        return schedule.rates
    if isinstance(schedule, (str, pathlib.Path)):
        return _m.load_rates(os.fspath(schedule), scenario)
    return np.asarray(schedule, dtype=float)


def uniform(scenario, budget=None):
    """The uniform schedule: the largest equal constant rate meeting every constraint."""
    return _m.uniform_rates(_budgeted(scenario, budget))


def load_schedule(path, scenario):
    """A schedule file's rates (N x M), checked against the scenario."""
    return _m.load_rates(os.fspath(path), scenario)


def write_schedule(path, scenario, schedule):
    """Writes a schedule file the programs read (--schedule)."""
    _m.write_rates(os.fspath(path), scenario, _rates(scenario, schedule))


def plan(scenario, surrogate="cov", budget=None, method="pqn", tolerance=1e-6, max_iterations=500,
         max_seconds=None, excluded=(), network_aware=False, warm_start=None, seed=1):
    """`coordinator plan`: the schedule minimizing the surrogate ("info", "cov"; "uniform"; "mc",
    the Monte Carlo planner, whose episodes follow `seed`) under C λ <= b, with the budget row
    set to `budget` when given."""
    s = _budgeted(scenario, budget)
    warm = None if warm_start is None else _rates(s, warm_start)
    d = _m.plan(s, surrogate, method, float(tolerance), int(max_iterations),
                None if max_seconds is None else float(max_seconds), [int(j) for j in excluded],
                bool(network_aware), warm, int(seed))
    d["bracket"] = Bracket(**d["bracket"])
    return Plan(**d)


def bracket(scenario, schedule=None, budget=None):
    """Corollary 1 for a schedule (default: uniform): Bracket(info, cov)."""
    s = _budgeted(scenario, budget)
    return Bracket(**_m.bracket(s, _rates(s, schedule)))


def _evaluation(d):
    if d.get("timetable") is not None:
        d["timetable"] = _evaluation(d["timetable"])
    return Evaluation(**d)


def evaluate(scenario, schedule=None, runs=1000, seed=1, threads=0, plant=True, arrivals=None):
    """`fusion_center evaluate`: `runs` episodes of the exact CD-KF under Poisson arrivals
    (with arrivals="timetable", the timetable's beside it; default the scenario's `arrivals:`)."""
    return _evaluation(_m.evaluate(scenario, _rates(scenario, schedule), int(runs), int(seed),
                                   int(threads), bool(plant), arrivals or ""))


def closed_loop(scenario, schedule=None, replan_every=1.0, surrogate="cov", runs=1000, seed=1,
                threads=0, switch_margin=0.3, time_scale=1.0):
    """`fusion_center evaluate --replan-every`: the rest of each episode re-planned every
    `replan_every` emulated seconds from the filter's covariance, against the open-loop plan."""
    return ClosedLoop(**_m.closed_loop(scenario, _rates(scenario, schedule), float(replan_every),
                                       surrogate, int(runs), int(seed), int(threads),
                                       float(switch_margin), float(time_scale)))


def trajectory(scenario, schedule=None, form="info", times=None):
    """The surrogate's covariance, P_info(t) = Ys(t)^-1 (form="info", eq. 11) or P_cov(t) (eq. 15):
    (times, P) with P of shape (len(times), n, n); without times, at the interval boundaries."""
    t = None if times is None else np.asarray(times, dtype=float)
    out_t, covariances = _m.trajectory(scenario, _rates(scenario, schedule), form, t)
    return np.asarray(out_t), np.stack(covariances)


def cdkf(scenario, times, sensors):
    """The exact CD-KF's covariance over measurements of `sensors[i]` at `times[i]`."""
    return Filtered(**_m.cdkf(scenario, np.asarray(times, dtype=float), [int(j) for j in sensors]))
