"""A run's report.json (docs/report.schema.json) as a typed object, its episodes as a pandas
DataFrame:

    r = sensornet.load_report("runs/default/report.json")
    r.status, r.exit_code_expected, [f.kind for f in r.faults]
    df = r.episodes                      # one row per episode; bracket_info, bracket_cov columns
    df[df.complete].realized_cost.mean()

A sweep's results (`sensornet sweep`) load the same way, one row per cell:

    cells = sensornet.load_sweep("sweeps/planners-vs-budget")
    cells.groupby(["planner", "budget"]).mean.mean()
"""

import dataclasses
import json
import os

__all__ = ["Fault", "Report", "load_report", "load_sweep"]

# The exit code of each status ("Exit status" in docs/guide/first-run.md).
_EXIT_CODES = {"completed": 0, "degraded": 3, "failed": 1, "interrupted": 1}


@dataclasses.dataclass(frozen=True)
class Fault:
    kind: str
    process: str
    detail: str
    episode: "int | None" = None
    sensor: "int | None" = None
    sensors: tuple = ()
    survived: "bool | None" = None


class Report:
    """The record of one run. Scalar sections are attributes (status, run_id, seed, summary,
    latency_s, clocks, scenario); `episodes` is a DataFrame; `raw` is the whole document."""

    def __init__(self, doc):
        if not isinstance(doc, dict) or "status" not in doc:
            raise ValueError("a report is a JSON object with a status (docs/report.schema.json)")
        self.raw = doc
        self.run_id = doc.get("run_id", "")
        self.status = doc["status"]
        self.seed = doc.get("seed")
        self.scenario = doc.get("scenario", {})
        self.summary = doc.get("summary", {})
        self.latency_s = doc.get("latency_s", {})
        self.clocks = doc.get("clocks", {})
        self.faults = [Fault(kind=f.get("kind", ""), process=f.get("process", ""),
                             detail=f.get("detail", ""), episode=f.get("episode"),
                             sensor=f.get("sensor"), sensors=tuple(f.get("sensors", ())),
                             survived=f.get("survived"))
                       for f in doc.get("faults", [])]

    @property
    def exit_code_expected(self):
        """The exit code the launcher gives a run of this status."""
        return _EXIT_CODES[self.status]

    @property
    def episodes(self):
        """One row per episode of per_episode; each bracket's ends as <name>_info and <name>_cov."""
        import pandas  # Debian: python3-pandas; only this needs it

        rows = []
        for e in self.raw.get("per_episode", []):
            row = {}
            for key, value in e.items():
                if isinstance(value, dict) and {"info", "cov"} <= value.keys():
                    row[f"{key}_info"], row[f"{key}_cov"] = value["info"], value["cov"]
                elif isinstance(value, (dict, list)):
                    row[key] = json.dumps(value)
                else:
                    row[key] = value
            rows.append(row)
        return pandas.DataFrame(rows)

    def __repr__(self):
        return (f"Report(run_id={self.run_id!r}, status={self.status!r}, "
                f"episodes={len(self.raw.get('per_episode', []))}, faults={len(self.faults)})")


def load_report(path):
    """Reads a report.json (or a sweep's JSON lines' `report` field) into a Report."""
    with open(os.fspath(path), encoding="utf-8") as f:
        return Report(json.load(f))


def load_sweep(path):
    """The results of `sensornet sweep` (its folder, or its results.jsonl) as a DataFrame: one
    row per cell (the last row of a cell run again), its axes and measurements as columns."""
    import pandas

    path = os.fspath(path)
    if os.path.isdir(path):
        path = os.path.join(path, "results.jsonl")
    rows = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.endswith("\n"):  # a last line torn by a crash is not a cell
                row = json.loads(line)
                rows[row["key"]] = row
    return pandas.DataFrame(list(rows.values()))
