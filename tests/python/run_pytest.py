"""Runs tests/python with pytest for ctest (tests/CMakeLists.txt's test_python).

Exits 77 (ctest's skip) with a message when NumPy or pytest is missing, so
that a machine without them skips the test rather than failing it; else
pytest's own exit status. Arguments are passed on to pytest.
"""
import os
import sys

for name in ("numpy", "pytest"):
    try:
        __import__(name)
    except ImportError:
        print(f"test_python: skipped: {sys.executable} has no {name} "
              f"(Debian: apt-get install python3-{name})")
        sys.exit(77)

import pytest  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", here] + sys.argv[1:]))
