"""The check of the Python tool tests: one line per check ("ok   ..." or "FAIL ..."), the
failures counted in `failures` for the test's exit status."""

failures = 0


def check(ok, what):
    """Prints the check's line and counts it when it failed."""
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += 0 if ok else 1
