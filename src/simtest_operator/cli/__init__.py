"""The `simtest` command line; every sub-command has its own module."""
