"""Helpers shared by the scenario tests: small OpenSCENARIO documents, HTTP route tables."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def xosc(description: str = "test", *, tags: str = "", category: str = "", body: str = "") -> str:
    """A small OpenSCENARIO document with simtest header properties."""
    props = ""
    if tags or category:
        props = "<Properties>"
        if tags:
            props += f'<Property name="simtest:tags" value="{tags}"/>'
        if category:
            props += f'<Property name="simtest:category" value="{category}"/>'
        props += "</Properties>"
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenSCENARIO>'
        f'<FileHeader revMajor="1" revMinor="1" date="2024-01-01T00:00:00" '
        f'description="{description}" author="t">{props}</FileHeader>'
        f"{body or '<Storyboard/>'}</OpenSCENARIO>\n"
    )


class Routes:
    """What the test server answers: path -> (status, body, headers), POST handler, request log."""

    def __init__(self) -> None:
        self.get: dict[str, tuple[int, bytes, dict[str, str]]] = {}
        self.post: Callable[[str, dict[str, str], Any], tuple[int, bytes]] | None = None
        self.requests: list[tuple[str, str, dict[str, str]]] = []
