"""The JSON Schemas of sim's files (``sim/schemas/``), each compiled once: what the
living room's and the site's readers check a file against before its meaning."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from jsonschema import Draft202012Validator

from userfiles.schema import validator

SCHEMAS_DIR = Path(__file__).resolve().parent / "schemas"


@cache
def schema(name: str) -> Draft202012Validator:
    """The validator of ``sim/schemas/NAME.schema.json``."""
    return validator(SCHEMAS_DIR, name)
