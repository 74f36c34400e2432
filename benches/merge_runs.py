#!/usr/bin/env python3
"""Merges `strandgraph bench --out` JSON files of one device, one backend
each, into one file for `strandgraph tables`: the full bench on both GPU
backends runs past the device tool's 10-minute limit, so each backend runs
in its own call (benches/device.sh).

    python3 benches/merge_runs.py ash/bench.json wgpu/bench.json > benches/results/h100.json
"""
import json
import sys

runs = [json.load(open(p)) for p in sys.argv[1:]]
out = dict(runs[0])
for key in ("cells", "devices", "roofline", "notes"):
    out[key] = [x for r in runs for x in r[key]]
for key in ("frames", "warmup", "size", "cpu_subgroup_width"):
    if any(r[key] != out[key] for r in runs):
        sys.exit(f"runs differ in {key}: {[r[key] for r in runs]}")
out["elapsed_s"] = sum(r["elapsed_s"] for r in runs)
backends = ", ".join(f"{d['backend']} ({r['elapsed_s']:.0f} s)" for r in runs for d in r["devices"])
out["notes"].append(f"merged from one run per backend (benches/merge_runs.py): {backends}")
json.dump(out, sys.stdout, indent=2, sort_keys=True)
print()
