"""tests/python/conftest.py: the markers of the Python module's tests.

memory: the resident-set checks (1,000 renders, 10^6 target evaluations);
a few seconds in all, run by default; `-m "not memory"` leaves them out.
"""


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "memory: resident-set checks of many renders and target calls (seconds)")
