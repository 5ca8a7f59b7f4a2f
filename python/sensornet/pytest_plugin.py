"""The pytest fixture: `pytest_plugins = ["sensornet.pytest_plugin"]`, then

    def test_my_sensor(sensornet_launch):
        run = sensornet_launch("scenarios/default.yaml", episodes=3, external_sensors=[2])
        ...
        assert run.wait().status == "completed"

Every run a test launched is stopped and removed when the test ends, passed or failed.
"""

import pytest

import sensornet


@pytest.fixture
def sensornet_launch():
    runs = []

    def launch(scenario, **options):
        run = sensornet.launch(scenario, **options)
        runs.append(run)
        return run

    yield launch
    for run in runs:
        run.close()
