"""Python participants in real runs (sensornet.Participant, topics as dicts): an external sensor
written here takes sensor 1 of the default scenario, and a scheduler written here re-plans a
run live. What is checked is recomputed from the report and from what crossed the wire."""

import math
import os
import pathlib
import random
import time

import sensornet

SOURCE = pathlib.Path(os.environ["SENSORNET_SOURCE_DIR"])
SCENARIO = SOURCE / "scenarios" / "default.yaml"
# Our processes compile the loopback configuration in; a participant of the user's reads it here.
os.environ.setdefault("CYCLONEDDS_URI", (SOURCE / "config" / "cyclonedds-loopback.xml").as_uri())


def domain_id(offset):
    return 100 + (os.getpid() + offset) % 50


class PythonSensor:
    """Speaks for one sensor (docs/wire-protocol.md, "Sensor"): Poisson arrivals at the rates of
    the schedule version in force, a Measurement at each, the EpisodeTally after T."""

    def __init__(self, participant, sensor, dim, seed):
        self.p, self.j, self.dim = participant, sensor, dim
        self.rng = random.Random(seed)
        self.scenarios = participant.reader("Scenario")
        self.schedules = participant.reader("Schedule")
        self.controls = participant.reader("EpisodeControl")
        mine = f"sensors/{sensor}"
        self.measurements = participant.writer("Measurement", mine)
        self.tallies = participant.writer("EpisodeTally", mine)
        self.statuses = participant.writer("SensorStatus", mine)
        self.scenario, self.versions, self.starts = None, [], []
        self.running, self.shut_down, self.sent_total = None, False, 0
        self.said, self.said_at = None, 0.0

    def in_force(self, episode, t):
        effective = [v for v in self.versions
                     if v["effective_episode"] < episode
                     or (v["effective_episode"] == episode and v["effective_time_s"] <= t)]
        return max(effective, key=lambda v: v["version"]) if effective else None

    def rate(self, episode, t):
        v = self.in_force(episode, t)
        n, m = self.scenario["intervals"], self.scenario["sensor_count"]
        i = min(int(t / (self.scenario["horizon_s"] / n)), n - 1)
        return v["rates_hz"][i * m + self.j] if v else 0.0

    def next_change(self, episode, t):
        width = self.scenario["horizon_s"] / self.scenario["intervals"]
        end = (math.floor(t / width + 1e-12) + 1) * width
        for v in self.versions:
            if v["effective_episode"] == episode and t < v["effective_time_s"] < end:
                end = v["effective_time_s"]
        return min(end, self.scenario["horizon_s"])

    def next_arrival(self, episode, t):
        budget = self.rng.expovariate(1.0)
        while t < self.scenario["horizon_s"]:
            end, rate = self.next_change(episode, t), self.rate(episode, t)
            if rate * (end - t) >= budget:
                return t + budget / rate
            budget -= rate * (end - t)
            t = end
        return math.inf

    # The arrivals (a draw of its own) and what it measures (nothing: z = 0); WorldSensor
    # overrides them.
    def first(self, episode):
        return self.next_arrival(episode, 0.0)

    def after(self, episode, running):
        return self.next_arrival(episode, running["next"])

    def measure(self, episode, seq, t):
        return [0.0] * self.dim

    def status(self, state):
        episode = self.running["start"]["episode"] if self.running else 0
        version = self.in_force(episode, 0.0)
        self.statuses.write({"sensor_id": self.j, "run_id": self.p.run_id, "state": state,
                             "episode": episode,
                             "schedule_version": version["version"] if version else 0,
                             "process_id": os.getpid(), "sent_total": self.sent_total,
                             "wall_time_ns": time.time_ns()})

    def step(self):
        run_id = self.p.run_id
        for s in self.scenarios.take():
            if s["run_id"] == run_id:
                self.scenario = s
        self.versions += [v for v in self.schedules.take() if v["run_id"] == run_id]
        for c in self.controls.take():
            if c["run_id"] != run_id:
                continue
            if c["command"] == "RUN_SHUTDOWN":
                self.shut_down = True
            elif c["command"] == "EPISODE_START":
                self.starts.append(c)
        if self.running is None and self.scenario and self.starts:
            start = self.starts.pop(0)
            self.running = {"start": start, "seq": 0, "next": self.first(start["episode"])}
        if self.running is not None:
            e = self.running
            k = e["start"]["episode"]
            now = (time.time_ns() - e["start"]["start_wall_time_ns"]) * 1e-9 * e["start"]["time_scale"]
            while e["next"] <= min(now, self.scenario["horizon_s"]):
                self.measurements.write({
                    "sensor_id": self.j, "run_id": run_id, "episode": k, "seq": e["seq"],
                    "emulated_time_s": e["next"],
                    "schedule_version": self.in_force(k, e["next"])["version"],
                    "publish_wall_time_ns": time.time_ns(),
                    "z": self.measure(k, e["seq"], e["next"])})
                e["seq"] += 1
                self.sent_total += 1
                e["next"] = self.after(k, e)
            if now >= self.scenario["horizon_s"]:
                self.tallies.write({"sensor_id": self.j, "run_id": run_id, "episode": k,
                                    "sent": e["seq"], "finished": True,
                                    "process_id": os.getpid(), "wall_time_ns": time.time_ns()})
                self.running = None
        ready = (self.scenario and self.versions and self.measurements.matched() > 0
                 and self.tallies.matched() > 0 and self.controls.matched() > 0)
        state = "SENSOR_RUNNING" if self.running else "SENSOR_READY" if ready else "SENSOR_STARTING"
        if state != self.said or time.monotonic() > self.said_at + 0.5:  # on change, and 2 Hz
            self.status(state)
            self.said, self.said_at = state, time.monotonic()


class WorldSensor(PythonSensor):
    """Draws its arrivals and measures the plant as our agents do, through sensornet.World."""

    def __init__(self, participant, sensor):
        super().__init__(participant, sensor, dim=0, seed=0)
        self.world, self.added, self.times = None, 0, []

    def world_now(self):
        if self.world is None:
            self.world = sensornet.World(self.scenario["yaml"], self.scenario["seed"])
            self.world.set_arrivals(self.scenario["arrivals"])
        for v in self.versions[self.added:]:
            self.world.add_schedule(v["version"], v["effective_episode"], v["effective_time_s"],
                                    v["rates_hz"])
        self.added = len(self.versions)
        return self.world

    def first(self, episode):
        self.times = list(self.world_now().arrivals(episode, self.j)[0])
        return self.times[0] if self.times else math.inf

    def after(self, episode, running):
        return self.times[running["seq"]] if running["seq"] < len(self.times) else math.inf

    def measure(self, episode, seq, t):
        return [float(v) for v in self.world.measure(episode, self.j, seq, t)]


def run_with(sensor_factory, domain, seed):
    """A run of the default scenario with sensor 1 spoken for by sensor_factory(participant)."""
    with sensornet.launch(SCENARIO, episodes=3, time_scale=4, seed=seed, external_sensors=[1],
                          extra_args=["--domain-id", str(domain), "--no-html"]) as run:
        participant = sensornet.Participant(run.run_id, domain_id=domain)
        sensor = sensor_factory(participant)
        deadline = time.monotonic() + 90
        while not sensor.shut_down and time.monotonic() < deadline:
            sensor.step()
            time.sleep(0.002)
        sensor.status("SENSOR_STOPPED")
        sensor.tallies.wait_for_acks(2.0)
        result = run.wait()
        participant.close()
    return sensor, result


def test_a_python_sensor_measuring_through_the_world_makes_our_agents_run():
    """Arrivals and measurements from sensornet.World: every episode's cost and NEES (which
    depends on every value measured) equal to the bit to a run of our own agents, same seed."""
    sensor, result = run_with(lambda p: WorldSensor(p, 1), domain_id(2), seed=7)
    with sensornet.launch(SCENARIO, episodes=3, time_scale=4, seed=7,
                          extra_args=["--domain-id", str(domain_id(3)), "--no-html"]) as run:
        ours = run.wait()
    assert result.status == "completed", result.faults
    assert ours.status == "completed", ours.faults
    assert sensor.sent_total > 10
    assert len(result.episodes) == len(ours.episodes) == 3
    for got, want in zip(result.episodes, ours.episodes):
        assert got["sent"] == want["sent"] and got["received"] == want["received"]
        assert got["realized_cost"] == want["realized_cost"], (got["episode"],)
        assert got["nees"] == want["nees"], (got["episode"], got["nees"], want["nees"])


def test_the_world_gives_numpy_arrays_and_refuses_bad_input():
    text = SCENARIO.read_text()
    w = sensornet.World(text, 7)
    x = w.state(0, 1.5)
    assert x.shape == (4,) and x.dtype.name == "float64"
    z, v = w.measure(0, 2, 3, 1.5), w.noise(0, 2, 3)
    assert z.shape == (2,)
    # Sensor 2 is the camera: H = [[1, 0, 0, 0], [0, 1, 0, 0]].
    assert abs(z[0] - (x[0] + v[0])) < 1e-12 and abs(z[1] - (x[1] + v[1])) < 1e-12
    for bad in (lambda: w.state(0, 99.0), lambda: w.measure(0, 9, 0, 1.0),
                lambda: sensornet.World("horizon: -1", 1)):
        try:
            bad()
        except ValueError as e:
            assert str(e)
        else:
            raise AssertionError("bad input was accepted")


def test_an_external_sensor_written_in_python_takes_its_role():
    domain = domain_id(0)
    with sensornet.launch(SCENARIO, episodes=3, time_scale=4, seed=7, external_sensors=[1],
                          extra_args=["--domain-id", str(domain), "--no-html"]) as run:
        participant = sensornet.Participant(run.run_id, domain_id=domain)
        sensor = PythonSensor(participant, sensor=1, dim=1, seed=3)
        deadline = time.monotonic() + 90
        while not sensor.shut_down and time.monotonic() < deadline:
            sensor.step()
            time.sleep(0.002)
        sensor.status("SENSOR_STOPPED")
        sensor.tallies.wait_for_acks(2.0)
        result = run.wait()
        participant.close()
    assert sensor.shut_down, "no RUN_SHUTDOWN came"
    assert result.exit_code == 0, result.errors
    assert result.status == "completed", result.faults
    assert len(result.episodes) == 3
    expected = sum(e["expected"][1] for e in result.episodes)
    sent = sum(e["sent"][1] for e in result.episodes)
    for e in result.episodes:
        assert e["complete"], e
        assert e["received"][1] == e["sent"][1] and e["lost"][1] == 0
    # Everything it wrote was accounted for, and its count is Poisson with the schedule's mean:
    # within 4.5 standard deviations (false alarm 7e-6).
    assert sent == sensor.sent_total
    assert expected > 10
    assert abs(sent - expected) <= 4.5 * math.sqrt(expected), (sent, expected)


def test_a_scheduler_written_in_python_replans_a_run_live():
    domain = domain_id(1)
    with sensornet.launch(SCENARIO, episodes=5, time_scale=2, seed=5,
                          extra_args=["--domain-id", str(domain), "--no-html"]) as run:
        p = sensornet.Participant(run.run_id, domain_id=domain)
        controls, replies = p.reader("EpisodeControl"), p.reader("CommandReply")
        schedules, commands = p.reader("Schedule"), p.writer("Command", "operator")
        command_id, reply, versions = None, None, {}
        deadline = time.monotonic() + 90
        while reply is None and time.monotonic() < deadline:
            for v in schedules.take():
                versions[v["version"]] = v
            started = [c for c in controls.take() if c["command"] == "EPISODE_START"]
            if command_id is None and any(c["episode"] >= 1 for c in started) and commands.matched():
                command_id = time.time_ns()
                commands.write({"run_id": run.run_id, "command_id": command_id,
                                "kind": "COMMAND_REPLAN", "surrogate": "cov",
                                "issuer": "test_participant.py", "issued_wall_time_ns": command_id})
            reply = next((r for r in replies.take() if r["command_id"] == command_id), None)
            time.sleep(0.01)
        assert reply is not None, "no CommandReply to the Command"
        assert reply["accepted"], reply
        version = reply["schedule_version"]
        while version not in versions and time.monotonic() < deadline:
            versions.update({v["version"]: v for v in schedules.take()})
            time.sleep(0.01)
        result = run.wait()
        p.close()
    assert version > 1
    assert versions[version]["surrogate"] == "cov"
    assert versions[version]["command_id"] == command_id
    assert result.exit_code == 0, result.errors
    recorded = {v["version"]: v for v in result.report["schedule_versions"]}
    assert recorded[version]["command_id"] == command_id
    assert recorded[version]["surrogate"] == "cov"
    n, m = versions[version]["intervals"], versions[version]["sensor_count"]
    assert [versions[version]["rates_hz"][i * m:(i + 1) * m] for i in range(n)] == \
        recorded[version]["rates"]
