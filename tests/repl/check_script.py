"""Pipes a script into `simit repl` and compares its output with the expected text (a ctest).

check_script.py SIMIT SCRIPT EXPECTED [--cwd DIR] [--args A...]

stdout and stderr are read as one stream, in the order written. In EXPECTED, `{{RE}}` inside
a line matches the regular expression RE (for timings); everything else must match exactly.
--args replaces the default command-line arguments (`repl`).
"""
import re
import subprocess
import sys


def line_matches(want, got):
    parts = re.split(r"\{\{(.*?)\}\}", want)
    pattern = "".join(re.escape(p) if i % 2 == 0 else "(?:" + p + ")" for i, p in enumerate(parts))
    return re.fullmatch(pattern, got) is not None


def main():
    args = sys.argv[1:]
    cwd = None
    if "--cwd" in args:
        i = args.index("--cwd")
        cwd = args[i + 1]
        del args[i:i + 2]
    command_args = ["repl"]
    if "--args" in args:
        i = args.index("--args")
        command_args = args[i + 1:]
        del args[i:]
    simit, script, expected = args[:3]
    with open(script) as f:
        result = subprocess.run([simit] + command_args, stdin=f, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, timeout=300, cwd=cwd)
    got = result.stdout.splitlines()
    want = open(expected).read().splitlines()
    bad = [i for i in range(max(len(got), len(want)))
           if i >= len(got) or i >= len(want) or not line_matches(want[i], got[i])]
    if result.returncode != 0 or bad:
        print("exit status", result.returncode)
        if bad:
            i = bad[0]
            print("first difference at line %d:" % (i + 1))
            print("  want: " + (want[i] if i < len(want) else "(end of output)"))
            print("  got:  " + (got[i] if i < len(got) else "(end of output)"))
        print("--- got\n" + result.stdout + "--- want\n" + "\n".join(want))
        sys.exit(1)


main()
