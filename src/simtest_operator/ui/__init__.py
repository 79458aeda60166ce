"""The results UI: ``simtest ui --database DSN`` serves the results database to a browser.

Pages (overview, runs, coverage, developer view with trajectory replay, comparisons, history and
flakiness) and their JSON twins under ``/api``, from :mod:`.queries` over a read-only
connection; :mod:`.server` is a standard-library WSGI app with jinja2 templates, and the little
JavaScript it ships (``templates/replay.js.j2``, served as ``/static/replay.js``) needs no
build step.
"""
