"""The math from Python (sensornet.offline) against the programs' own numbers for the same inputs
(`coordinator plan`, `fusion_center evaluate`, run here as a user runs them), and against closed
forms where one exists (a scalar plant). Every random quantity has a fixed seed."""

import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import sensornet

SOURCE = pathlib.Path(os.environ["SENSORNET_SOURCE_DIR"])
COORDINATOR = os.environ["SENSORNET_COORDINATOR"]
FUSION_CENTER = os.environ["SENSORNET_FUSION_CENTER"]
LAUNCHER = os.environ["SENSORNET_PROGRAM"]

# The first paper's random plant, small: a non-symmetric A with stable and unstable modes.
RANDOM = """name: python-math
horizon: 2.0
intervals: 8
random:
  states: 4
  sensors: 6
  seed: {seed}
  budget: {budget}
  noise_scale: {noise}
"""

# A scalar plant with closed forms: dx = a x dt + dw (E dw^2 = q dt), one sensor z = h x + v.
SCALAR = """name: scalar
horizon: 1.5
intervals: 3
plant:
  A: [[{a}]]
  Q: [[{q}]]
  P0: [[{p0}]]
sensors:
  - H: [[{h}]]
    R: [[{r}]]
cost:
  W: [[{w}]]
  WT: [[1]]
constraints:
  C: [[1]]
  b: [5]
"""


def run_json(*argv):
    done = subprocess.run(argv, capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture
def random_file(tmp_path):
    def make(seed=5, budget=4.0, noise=1.0):
        path = tmp_path / f"random-{seed}-{budget}-{noise}.yaml"
        path.write_text(RANDOM.format(seed=seed, budget=budget, noise=noise))
        return path
    return make


def test_a_scenario_file_and_the_generator_give_the_same_plant(random_file):
    from_file = sensornet.load_scenario(random_file(seed=5, budget=4.0, noise=2.0))
    made = sensornet.random_scenario(states=4, sensors=6, seed=5, budget=4.0, noise_scale=2.0,
                                     horizon=2.0, intervals=8)
    for name in ("A", "Q", "P0", "W", "WT", "C", "b"):
        assert np.array_equal(getattr(from_file, name), getattr(made, name)), name
    assert all(np.array_equal(x, y) for x, y in zip(from_file.R, made.R))


def test_matrices_keep_their_orientation():
    s = sensornet.load_scenario(SOURCE / "scenarios" / "default.yaml")
    assert s.A[0, 2] == 1.0 and s.A[2, 0] == 0.0  # dx/dt = vx, not the reverse
    assert s.C.shape == (2, 6) and s.C[1, 2] == 2.0 and s.b.tolist() == [12.0, 6.0]
    assert s.H[2].shape == (2, 4) and s.R[2][0, 1] == 1.0
    assert sensornet.uniform(s).shape == (30, 6)  # intervals x sensors


@pytest.mark.parametrize("surrogate", ["info", "cov"])
def test_a_plan_is_coordinator_plans_to_the_last_bit(tmp_path, random_file, surrogate):
    scenario = random_file(seed=7, budget=3.0)
    out = tmp_path / "plan.json"
    printed = run_json(COORDINATOR, "plan", "--scenario", str(scenario), "--surrogate", surrogate,
                       "--out", str(out), "--json")
    # The same plant and a budget given here instead of in the file.
    p = sensornet.plan(sensornet.load_scenario(random_file(seed=7, budget=9.0)),
                       surrogate=surrogate, budget=3.0)
    assert p.objective == printed["objective"]
    assert p.bracket.info == printed["bracket"]["info"]
    assert p.bracket.cov == printed["bracket"]["cov"]
    assert p.iterations == printed["iterations"]
    assert np.array_equal(p.rates, np.array(json.loads(out.read_text())["rates"]))
    assert p.solved and p.bracket.info <= p.bracket.cov
    # The plan meets the budget it was given, and spends it (the rates bind 1'λ <= 3).
    assert np.all(p.rates.sum(axis=1) <= 3.0 + 1e-9)
    assert p.rates.sum(axis=1).max() == pytest.approx(3.0, rel=1e-6)
    # Its bracket is what bracket() gives for its rates.
    again = sensornet.bracket(sensornet.load_scenario(scenario), p)
    assert again == p.bracket


def test_an_energy_budget_is_met_binds_and_is_what_coordinator_plans(tmp_path, random_file):
    # A budget of 1.5 expected measurements per sensor over the 2 s horizon, against the
    # 3 Hz x 2 s = 6 that the rate budget lets one sensor take.
    text = random_file(seed=7, budget=3.0).read_text().replace("  noise_scale:", "  energy: 1.5\n  noise_scale:")
    scenario = tmp_path / "energy.yaml"
    scenario.write_text(text)
    out = tmp_path / "plan.json"
    printed = run_json(COORDINATOR, "plan", "--scenario", str(scenario), "--surrogate", "info",
                       "--out", str(out), "--json")
    s = sensornet.random_scenario(states=4, sensors=6, seed=7, budget=3.0, horizon=2.0,
                                  intervals=8, energy=1.5)
    assert s.energy.tolist() == [1.5] * 6
    p = sensornet.plan(s, surrogate="info")
    assert p.objective == printed["objective"]
    assert np.array_equal(p.rates, np.array(json.loads(out.read_text())["rates"]))
    used = p.rates.sum(axis=0) * (2.0 / 8)  # ∫λ_j dt over 8 intervals of 0.25 s
    assert np.all(used <= 1.5 * (1 + 1e-12))
    assert np.sum(used >= 1.5 * (1 - 1e-6)) >= 1  # the budget binds somewhere
    free = sensornet.plan(sensornet.random_scenario(states=4, sensors=6, seed=7, budget=3.0,
                                                    horizon=2.0, intervals=8), surrogate="info")
    assert (free.rates.sum(axis=0) * 0.25).max() > 1.5  # which it would not without it
    assert free.objective < p.objective
    # The same budget given to the plant of the file, per sensor.
    assert sensornet.plan(sensornet.load_scenario(random_file(seed=7, budget=3.0)).with_energy(
        [1.5] * 6), surrogate="info").objective == p.objective
    with pytest.raises(ValueError, match="energy"):
        s.with_energy([1.0, 2.0])


def test_evaluate_is_fusion_center_evaluate_for_the_same_seed(tmp_path):
    # The default scenario: a non-symmetric A, sensors of one and two rows, two constraint rows.
    scenario = SOURCE / "scenarios" / "default.yaml"
    s = sensornet.load_scenario(scenario)
    p = sensornet.plan(s, surrogate="info")
    # Rates that vary in time and across sensors, written here and read by the program.
    assert np.ptp(p.rates, axis=0).max() > 0 and np.ptp(p.rates, axis=1).max() > 0
    schedule = tmp_path / "plan.json"
    sensornet.write_schedule(schedule, s, p)
    printed = run_json(FUSION_CENTER, "evaluate", "--scenario", str(scenario), "--schedule",
                       str(schedule), "--runs", "400", "--seed", "11", "--json")
    e = sensornet.evaluate(s, schedule, runs=400, seed=11, threads=1)
    assert e.mean == printed["mc"]["mean"]
    assert e.ci95 == printed["mc"]["ci95"]
    assert e.nees_mean == printed["nees"]
    assert e.runs == 400 and e.episode_costs.shape == (400,)
    assert e.mean == pytest.approx(e.episode_costs.mean(), rel=1e-12)
    assert printed["bracket"] == {"info": p.bracket.info, "cov": p.bracket.cov}
    # Another seed is another sample (the seed is used).
    assert sensornet.evaluate(s, schedule, runs=400, seed=12).mean != e.mean


def test_the_closed_loop_is_fusion_center_evaluates(tmp_path, random_file):
    scenario = random_file(seed=4, budget=4.0)
    s = sensornet.load_scenario(scenario)
    printed = run_json(FUSION_CENTER, "evaluate", "--scenario", str(scenario), "--replan-every",
                       "0.5", "--surrogate", "info", "--runs", "40", "--seed", "3", "--json")
    c = sensornet.closed_loop(s, None, replan_every=0.5, surrogate="info", runs=40, seed=3)
    assert c.mean == printed["closed_loop"]["mean"]
    assert c.open_mean == printed["open_loop"]["mean"]
    assert c.gain["mean"] == printed["closed_minus_open"]["mean"]
    assert c.episode_costs.shape == (40,)


def scalar(a=0.7, q=2.0, p0=3.0, h=1.5, r=0.8, w=0.0):
    return sensornet.parse_scenario(SCALAR.format(a=a, q=q, p0=p0, h=h, r=r, w=w))


def open_loop_variance(a, q, p, t):
    """Var of dx = a x dt + dw after t from p: e^{2at} p + q (e^{2at} - 1) / (2a)."""
    g = math.exp(2 * a * t)
    return g * p + q * (g - 1) / (2 * a)


def test_without_measurements_both_surrogates_follow_the_closed_form():
    s = scalar()
    times = np.linspace(0.0, 1.5, 16)
    for form in ("info", "cov"):
        t, P = sensornet.trajectory(s, np.zeros((3, 1)), form=form, times=times)
        assert P.shape == (16, 1, 1)
        for ti, pi in zip(t, P[:, 0, 0]):
            assert pi == pytest.approx(open_loop_variance(0.7, 2.0, 3.0, ti), rel=1e-8)
    # At the interval boundaries when no times are given.
    t, _ = sensornet.trajectory(s, np.zeros((3, 1)))
    assert np.allclose(t, [0.0, 0.5, 1.0, 1.5])


def test_the_exact_filter_over_given_instants_is_the_closed_form():
    a, q, p0, h, r = 0.7, 2.0, 3.0, 1.5, 0.8
    s = scalar(a, q, p0, h, r)
    # Out of order on purpose: the filter takes them in time order.
    f = sensornet.cdkf(s, times=[1.1, 0.4], sensors=[0, 0])
    p = open_loop_variance(a, q, p0, 0.4)
    p = p * r / (r + h * h * p)
    p = open_loop_variance(a, q, p, 0.7)
    p = p * r / (r + h * h * p)
    p = open_loop_variance(a, q, p, 0.4)
    assert f.covariance[0, 0] == pytest.approx(p, rel=1e-12)
    assert f.cost == pytest.approx(p, rel=1e-12)  # W = 0, W_T = 1: J = P(T)
    assert f.running_cost == 0.0


def test_bad_input_is_one_line_naming_what_is_wrong(random_file):
    s = sensornet.load_scenario(random_file())
    with pytest.raises(ValueError, match="8 intervals x 6 sensors, got 3 x 6"):
        sensornet.bracket(s, np.ones((3, 6)))
    with pytest.raises(ValueError, match="C λ <= b"):
        sensornet.bracket(s, np.full((8, 6), 100.0))
    with pytest.raises(ValueError, match="surrogate"):
        sensornet.plan(s, surrogate="best")
    with pytest.raises(ValueError, match="sensors\\[0\\]"):
        sensornet.cdkf(s, times=[0.1], sensors=[6])
    with pytest.raises(ValueError, match="one constraint row"):
        sensornet.load_scenario(SOURCE / "scenarios" / "default.yaml").with_budget(3.0)
    with pytest.raises(sensornet.InputError):
        sensornet.parse_scenario("horizon: -1\n")


def test_a_sweeps_cells_load_as_a_table_and_equal_the_functions(tmp_path, random_file):
    scenario = random_file(seed=6, budget=3.0)
    experiment = tmp_path / "e.yaml"
    experiment.write_text(f"scenarios: [{{file: {scenario}, budget: [2, 3]}}]\n"
                          "planners: [info, uniform]\nruns: 200\nseeds: [5]\n")
    done = subprocess.run([LAUNCHER, "sweep", str(experiment), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr
    cells = sensornet.load_sweep(tmp_path / "out")
    assert len(cells) == 4 and set(cells.status) == {"ok"}
    assert sorted(cells.budget.unique()) == [2.0, 3.0]
    s = sensornet.load_scenario(scenario)
    for row in cells.itertuples():
        p = sensornet.plan(s, surrogate=row.planner, budget=row.budget)
        e = sensornet.evaluate(s.with_budget(row.budget), p, runs=200, seed=5)
        assert (row.bracket_info, row.bracket_cov) == (p.bracket.info, p.bracket.cov)
        assert row.mean == e.mean and row.ci95 == e.ci95
