"""sensornet from Python test suites: launch a run, wait for it, read its report.

    import sensornet
    with sensornet.launch("scenarios/default.yaml", episodes=3, external_sensors=[2, 5]) as run:
        ...  # start your participant with run.run_id
        result = run.wait()
    assert result.status == "completed", result.faults

The run gets a run id and a private folder of its own and is stopped (Ctrl-C to the launcher,
then SIGKILL of its process group) when the `with` block ends or close() is called, also when
the test failed first. The pytest fixture is in sensornet.pytest_plugin.

A participant of a run reads and writes its topics (docs/wire-protocol.md) as dicts, with the
QoS the run's own processes use, enough to write an external sensor or a scheduler:

    p = sensornet.Participant(run.run_id, domain_id=7)
    schedules = p.reader("Schedule")                 # partition sensornet/<run id>
    measurements = p.writer("Measurement", "sensors/1")
    measurements.write({"sensor_id": 1, "run_id": run.run_id, "episode": 0, "seq": 0,
                        "emulated_time_s": 0.1, "z": [0.0]})
    for s in schedules.take(): print(s["version"], s["rates_hz"])

Fields a dict leaves out are zero or empty; a field the type does not have, or a value of the
wrong kind, raises KeyError or TypeError naming it; enums are their IDL names
("EPISODE_START"). Cyclone finds its configuration in CYCLONEDDS_URI as usual.

The emulated world of a run (the plant's truth, the noise and the arrivals our agents draw, as
numpy arrays, bit for bit theirs) from its Scenario sample, for a sensor that measures the plant:

    w = sensornet.World(scenario["yaml"], scenario["seed"])
    w.add_schedule(v["version"], v["effective_episode"], v["effective_time_s"], v["rates_hz"])
    times, versions = w.arrivals(episode, sensor)
    z = w.measure(episode, sensor, seq, times[seq])

The math of the programs without a run (sensornet.offline): scenarios, plan(), bracket(),
evaluate() (the Monte Carlo of `fusion_center evaluate`, the same numbers for the same seed),
closed_loop(), the surrogates' trajectory() and the exact cdkf(); and a report.json as a typed
Report with its episodes as a pandas DataFrame (sensornet.report):

    s = sensornet.load_scenario("scenarios/default.yaml")
    p = sensornet.plan(s, surrogate="info", budget=4.0)
    e = sensornet.evaluate(s.with_budget(4.0), p, runs=2000, seed=7)
    df = sensornet.load_report("report.json").episodes
"""

import datetime
import json
import os
import pathlib
import shutil

from ._sensornet import LaunchOptions as _LaunchOptions
from ._sensornet import LaunchedRun as _LaunchedRun
from ._sensornet import Participant, World, topic_names
from . import offline, report
from .offline import *  # noqa: F401,F403 (listed in offline.__all__)
from .report import Fault, Report, load_report, load_sweep

__all__ = (["launch", "Run", "Result", "program", "Participant", "World", "topic_names",
            "Fault", "Report", "load_report", "load_sweep"] + offline.__all__)


def program():
    """The sensornet program: $SENSORNET_PROGRAM, the one installed with this package, or PATH."""
    if os.environ.get("SENSORNET_PROGRAM"):
        return pathlib.Path(os.environ["SENSORNET_PROGRAM"])
    here = pathlib.Path(__file__).resolve()
    for prefix in here.parents:  # <prefix>/lib/python3/dist-packages/sensornet/__init__.py
        candidate = prefix / "bin" / "sensornet"
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    found = shutil.which("sensornet")
    if found is None:
        raise RuntimeError("no sensornet program: set SENSORNET_PROGRAM or put it on the PATH")
    return pathlib.Path(found)


class Result:
    """How a run ended: exit_code, status, episodes, faults, and the whole report (a dict)."""

    def __init__(self, exit_code, output, errors, report_json):
        self.exit_code = exit_code
        self.output = output
        self.errors = errors
        self.report = json.loads(report_json) if report_json else {}
        if not isinstance(self.report, dict):
            self.report = {}
        self.status = self.report.get("status", "")
        self.episodes = self.report.get("per_episode", [])
        self.summary = self.report.get("summary", {})
        self.faults = [f"{f.get('kind')} in {f.get('process')}: {f.get('detail')}"
                       for f in self.report.get("faults", [])]

    @property
    def record(self):
        """The report as a typed Report (episodes as a DataFrame)."""
        return Report(self.report)

    def __repr__(self):
        return f"Result(exit_code={self.exit_code}, status={self.status!r}, episodes={len(self.episodes)})"


class Run:
    """A launched run; see launch()."""

    def __init__(self, scenario, episodes=4, time_scale=4.0, seed=1, external_sensors=(),
                 external_fusion_center=False, reference_fusion=False, require="",
                 extra_args=(), timeout_s=300):
        options = _LaunchOptions()
        options.program = str(program())
        options.scenario = str(scenario)
        options.episodes = int(episodes)
        options.time_scale = float(time_scale)
        options.seed = int(seed)
        options.external_sensors = [int(j) for j in external_sensors]
        options.external_fusion_center = bool(external_fusion_center)
        options.reference_fusion = bool(reference_fusion)
        options.require = str(require)
        options.extra_args = [str(a) for a in extra_args]
        options.timeout = datetime.timedelta(seconds=timeout_s)
        self._run = _LaunchedRun(options)
        self._result = None

    @property
    def run_id(self):
        return self._run.run_id

    @property
    def log_dir(self):
        return pathlib.Path(self._run.log_dir)

    @property
    def launcher_pid(self):
        return self._run.launcher_pid

    def wait(self):
        """Waits for the run's end (stopping it at the timeout) and returns its Result."""
        if self._result is None:
            self._result = Result(*self._run.wait())
        return self._result

    def close(self):
        """Stops the run if it still goes and removes its files."""
        if self._run is not None:
            run, self._run = self._run, None
            del run  # the C++ destructor stops the run

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def launch(scenario, **options):
    """Starts `sensornet launch SCENARIO` with these options (see Run); returns the Run."""
    return Run(scenario, **options)
