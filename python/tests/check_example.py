"""Runs one docs/examples script and checks it (ctest python.example.*).

    check_example.py SCRIPT OUT_DIR CHECK...

The script runs as `python3 SCRIPT --out OUT_DIR` and must exit with 0 and write
OUT_DIR/summary.json. Each CHECK is `KEY<VALUE`, `KEY<=VALUE`, `KEY>VALUE`, `KEY>=VALUE` or
`KEY==VALUE` on a number of the summary (`KEY==true` / `false` for booleans), or `file:NAME`: a
non-empty file OUT_DIR/NAME. Exit 0 when all hold, 1 otherwise (every failure is printed).
"""

import json
import operator
import pathlib
import re
import shutil
import subprocess
import sys

OPS = [("<=", operator.le), (">=", operator.ge), ("==", operator.eq), ("<", operator.lt),
       (">", operator.gt)]


def check(summary, out, spec):
    if spec.startswith("file:"):
        path = out / spec[5:]
        ok = path.is_file() and path.stat().st_size > 0
        return ok, "%s: %s" % (path, "present" if ok else "missing or empty")
    for symbol, op in OPS:
        key, sep, value = spec.partition(symbol)
        if sep and re.fullmatch(r"[A-Za-z0-9_]+", key):
            if key not in summary:
                return False, "%s: not in summary.json" % key
            actual = summary[key]
            if value in ("true", "false"):
                expected = value == "true"
                return actual is expected, "%s = %s (expected %s)" % (key, actual, value)
            ok = op(float(actual), float(value))
            return ok, "%s = %r %s %s" % (key, actual, symbol, value)
    return False, "bad check %r" % spec


def main(argv):
    script, out = pathlib.Path(argv[1]), pathlib.Path(argv[2])
    shutil.rmtree(out, ignore_errors=True)
    run = subprocess.run([sys.executable, str(script), "--out", str(out)])
    if run.returncode != 0:
        print("FAIL: %s exited with %d" % (script.name, run.returncode))
        return 1
    summary = json.loads((out / "summary.json").read_text())
    failed = 0
    for spec in argv[3:]:
        ok, message = check(summary, out, spec)
        print("%s %s" % ("ok  " if ok else "FAIL", message))
        failed += not ok
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
