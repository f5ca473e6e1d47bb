#!/usr/bin/env python3
"""Estimates ctest -jN's wall time from serial per-test times (docs/BENCHMARKS.md, "CI time").

  ctest --test-dir build/default --show-only=json-v1 > tests.json
  python3 tools/ctest-j2-estimate.py TIMES tests.json [LABEL] [--jobs N]

TIMES is a serial ctest log (its "Test #k: name .... Passed 1.23 sec" lines) or a
Testing/Temporary/CTestCostData.txt. Tests labelled `bench`, and tests without a time, are left
out. The schedule is greedy, longest first (as ctest orders tests by recorded cost); RUN_SERIAL
tests run alone. It assumes each test keeps one core busy: an estimate for an unloaded machine
with N cores, not a measurement.
"""
import argparse
import json
import re

ap = argparse.ArgumentParser()
ap.add_argument("times")
ap.add_argument("tests_json")
ap.add_argument("label", nargs="?")
ap.add_argument("--jobs", type=int, default=2)
a = ap.parse_args()

times = {}
with open(a.times) as f:
    if a.times.endswith("CTestCostData.txt"):
        for line in f:
            if line.startswith("---"):
                break
            p = line.rstrip("\n").rsplit(" ", 2)
            if len(p) == 3:
                times[p[0]] = float(p[2])
    else:
        for line in f:
            m = re.match(r"\s*\d+/\d+ Test\s+#\d+: (.*?) \.+\s*(?:\*\*\*)?\w+\s+([\d.]+) sec", line)
            if m:
                times[m.group(1)] = float(m.group(2))

serial_part, parallel = 0.0, []
with open(a.tests_json) as f:
    for t in json.load(f)["tests"]:
        props = {p["name"]: p["value"] for p in t.get("properties", [])}
        labels = props.get("LABELS", [])
        if "bench" in labels or (a.label and a.label not in labels) or t["name"] not in times:
            continue
        if props.get("RUN_SERIAL"):
            serial_part += times[t["name"]]
        else:
            parallel.append(times[t["name"]])
slots = [0.0] * a.jobs
for x in sorted(parallel, reverse=True):
    slots[slots.index(min(slots))] += x
total = serial_part + sum(parallel)
print(f"{len(parallel)} parallel + RUN_SERIAL tests: serial sum {total:.0f} s; "
      f"-j{a.jobs} estimate {max(slots) + serial_part:.0f} s (RUN_SERIAL {serial_part:.0f} s)")
