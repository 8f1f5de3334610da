"""The Python tests' main: every function test_* of a module, by name, then a count."""


def run_all(names):
    """names: the test module's globals(); a failing test raises, ending the run."""
    tests = [v for k, v in sorted(names.items()) if k.startswith("test_")]
    for t in tests:
        t()
        print("ok", t.__name__)
    print("%d passed, 0 failed" % len(tests))
