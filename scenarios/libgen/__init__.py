"""Generator of the project's scenario library (roads, 200-scenario suite, smoke set).

Run `python scenarios/generate.py`; see scenarios/README.md.
"""
