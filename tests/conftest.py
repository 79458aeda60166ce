"""Root conftest: loads the shared fixture plugins (see tests/fixtures/)."""

pytest_plugins = [
    "tests.fixtures.cluster",
    "tests.fixtures.golden",
    "tests.fixtures.postgres",
    "tests.fixtures.realnode",
]
