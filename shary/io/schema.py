"""The JSON Schemas of shary's files, shipped in ``shary/schemas/`` so that
editors can use them too (``# yaml-language-server: $schema=…``)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from jsonschema import Draft202012Validator

from userfiles import schema as checks
from userfiles.errors import Problem
from userfiles.yamlsafe import Located

FOLDER = Path(__file__).resolve().parents[1] / "schemas"


@cache
def validator(name: str) -> Draft202012Validator:
    """The validator of ``shary/schemas/NAME.schema.json``, built once."""
    return checks.validator(FOLDER, name)


def check(located: Located, name: str) -> list[Problem]:
    """Every violation of ``shary/schemas/NAME.schema.json`` in ``located``."""
    return checks.check(located, validator(name))
