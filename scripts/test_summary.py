#!/usr/bin/env python3
"""Prints, last, what failed in each build's test log: the test's name, its result
and the end of its output (from the start of a sanitizer's report, whose first
lines name what raced or broke), so that a log read from its tail names the failure.
Arguments: the build directories (build, build-san, build-tsan)."""
import json
import re
import sys

REPORT = re.compile(r"^(WARNING|ERROR): (ThreadSanitizer|AddressSanitizer|LeakSanitizer)|"
                    r"runtime error: ")

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
        lines = ((r.get("stdout") or "") + (r.get("stderr") or "")).splitlines()
        first = next((i for i, line in enumerate(lines) if REPORT.search(line)), len(lines))
        for line in lines[first:first + 80] if first < len(lines) - 40 else lines[-40:]:
            print(f"   {line}")
sys.exit(1 if failed_any else 0)
