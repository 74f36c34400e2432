#!/usr/bin/env python3
"""Merges `strandgraph bench --out` JSON files of one device, one backend
each, into one file for `strandgraph tables`: the full bench on both GPU
backends runs past the device tool's 10-minute limit, so each backend runs
in its own call (benches/device.sh).

    python3 benches/merge_runs.py ash/bench.json wgpu/bench.json > benches/results/h100.json

With `--add PIPELINE`, the first file is an already merged result and the
cells of PIPELINE's rows (say, "HW mesh"), or of one row ("Lipp: SWR 1"),
from the later runs of the same device are added to it, replacing those it
had on the backends the later runs measured; the notes say which runs.

    python3 benches/merge_runs.py --add "HW mesh" benches/results/h100.json ash/bench.json wgpu/bench.json

With `--rows`, the runs are of one backend, each timing other rows (a
bench whose rows run past one call's limit, split by `--row`): their cells
are joined in order, and a row measured twice is an error.

    python3 benches/merge_runs.py --rows first/bench.json rest/bench.json > benches/results/h200-lipp.json
"""
import json
import sys

args = sys.argv[1:]
add = None
rows = args[:1] == ["--rows"]
if rows:
    args = args[1:]
elif args[:1] == ["--add"]:
    add, args = args[1], args[2:]
runs = [json.load(open(p)) for p in args]
partial = [p for p, r in zip(args, runs) if r.get("partial")]
for key in ("frames", "warmup", "size", "cpu_subgroup_width"):
    if any(r[key] != runs[0][key] for r in runs):
        sys.exit(f"runs differ in {key}: {[r[key] for r in runs]}")
devices = {d["device"].split(" (")[0] for r in runs for d in r["devices"]}
if len(devices) != 1:
    sys.exit(f"runs of different devices: {sorted(devices)}")
out = dict(runs[0])
backends = ", ".join(f"{d['backend']} ({r['elapsed_s']:.0f} s)" for r in runs[1 if add else 0:] for d in r["devices"])
if rows:
    key = lambda c: (c["backend"], c["pipeline"], c["variant"], c["view"])
    seen = set()
    for c in (c for r in runs for c in r["cells"]):
        if key(c) in seen:
            sys.exit(f"measured in two runs: {key(c)}")
        seen.add(key(c))
    out["cells"] = [c for r in runs for c in r["cells"]]
    out["elapsed_s"] = sum(r["elapsed_s"] for r in runs)
    out["notes"] = out["notes"] + [f"rows joined from runs of one backend (benches/merge_runs.py --rows): {backends}"]
elif add is None:
    for key in ("cells", "devices", "roofline", "notes"):
        out[key] = [x for r in runs for x in r[key]]
    out["elapsed_s"] = sum(r["elapsed_s"] for r in runs)
    out["notes"].append(f"merged from one run per backend (benches/merge_runs.py): {backends}")
else:
    # "Lipp" adds a pipeline's rows; "Lipp: SWR 1" one row of it.
    row_of = lambda c: add in (c["pipeline"], f'{c["pipeline"]}: {c["variant"]}')
    added = [c for r in runs[1:] for c in r["cells"] if row_of(c)]
    if not added:
        sys.exit(f"no `{add}` cells in the added runs")
    measured = {c["backend"] for c in added}
    replaced = lambda c: row_of(c) and c["backend"] in measured
    # In place of the cells they replace, so the tables keep their row order.
    # A new row goes after its pipeline's last cell.
    same = [i for i, c in enumerate(out["cells"]) if c["pipeline"] == added[0]["pipeline"]]
    at = next((i for i, c in enumerate(out["cells"]) if replaced(c)), same[-1] + 1 if same else len(out["cells"]))
    kept = [c for c in out["cells"] if not replaced(c)]
    out["cells"] = kept[:at] + added + kept[at:]
    out["elapsed_s"] = out["elapsed_s"] + sum(r["elapsed_s"] for r in runs[1:])
    out["notes"] = out["notes"] + [f"`{add}` rows added from later runs on the same device (benches/merge_runs.py --add): {backends}"]
if partial:
    out["notes"].append(f"partial runs (stopped before their last row; their finished rows are kept): {', '.join(partial)}")
out["partial"] = False
json.dump(out, sys.stdout, indent=2, sort_keys=True)
print()
