#!/usr/bin/env python3
"""Prints, last, what failed in each build's test log: the test's name, its result
and the end of its output, so that a log read from its tail names the failure."""
import json
import sys

failed_any = False
for build in sys.argv[1:]:
    try:
        with open(f"{build}/meson-logs/testlog.json", encoding="utf-8") as f:
            rows = [json.loads(line) for line in f if line.strip()]
    except OSError as e:
        print(f"== {build}: no test log ({e.strerror})")
        failed_any = True
        continue
    bad = [r for r in rows if r.get("result") not in ("OK", "EXPECTEDFAIL", "SKIP")]
    print(f"== {build}: {len(rows) - len(bad)} of {len(rows)} tests passed")
    for r in bad:
        failed_any = True
        print(f"== {build}: {r['name']}: {r.get('result')} after {r.get('duration', 0):.1f} s")
        out = (r.get("stdout") or "") + (r.get("stderr") or "")
        for line in out.splitlines()[-40:]:
            print(f"   {line}")
sys.exit(1 if failed_any else 0)
