"""Numbered schema migrations (``NNNN_name.sql``), applied in order by :mod:`..migrating`.

Kept as a package so :func:`importlib.resources.files` finds them in a wheel
as well as in a checkout.
"""
