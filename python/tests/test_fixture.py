"""The Python fixture against real runs: the default scenario's report recomputed from its own
episodes, and a run a test abandons stopped with nothing left running."""

import os
import pathlib
import time

import pytest

import sensornet

pytest_plugins = ["sensornet.pytest_plugin"]

SCENARIO = pathlib.Path(os.environ["SENSORNET_SOURCE_DIR"]) / "scenarios" / "default.yaml"


def processes_of(run_id):
    found = 0
    for entry in pathlib.Path("/proc").iterdir():
        try:
            if run_id.encode() in (entry / "cmdline").read_bytes():
                found += 1
        except OSError:
            pass
    return found


def test_a_run_completes_and_accounts_for_every_measurement(sensornet_launch):
    run = sensornet_launch(SCENARIO, episodes=3, time_scale=4, seed=11)
    result = run.wait()
    assert result.exit_code == 0, result.errors
    assert result.status == "completed"
    assert len(result.episodes) == 3
    for e in result.episodes:
        assert e["complete"]
        for sent, received, lost in zip(e["sent"], e["received"], e["lost"]):
            assert sent == received + lost and lost == 0
    mean = sum(e["realized_cost"] for e in result.episodes) / 3
    assert result.summary["mean"] == pytest.approx(mean, rel=1e-12)
    # The same report, typed: its episodes as a DataFrame, one row each, brackets split.
    record = result.record
    assert record.status == "completed" and record.exit_code_expected == result.exit_code
    df = record.episodes
    assert list(df.episode) == [0, 1, 2]
    assert list(df.realized_cost) == [e["realized_cost"] for e in result.episodes]
    assert list(df.bracket_info) == [e["bracket"]["info"] for e in result.episodes]
    assert (df.bracket_info <= df.bracket_cov).all()
    assert record.faults == []


def test_a_run_left_early_is_stopped_and_leaves_no_process():
    with sensornet.launch(SCENARIO, episodes=50, time_scale=2) as run:
        run_id, pid = run.run_id, run.launcher_pid
        time.sleep(3)
        assert processes_of(run_id) > 1
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    deadline = time.monotonic() + 10
    while processes_of(run_id) > 0 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert processes_of(run_id) == 0


def test_a_failed_requirement_is_exit_four(sensornet_launch):
    result = sensornet_launch(SCENARIO, episodes=2, require="mean<=0.001").wait()
    assert result.exit_code == 4, result.errors
    assert result.status == "completed"
