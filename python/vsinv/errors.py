"""The package's errors: the exception classes (each extends ``ValueError`` and carries its
``kind`` and structured attributes) and the tables they are built from (``ERROR_CLASSES``,
``ERROR_KINDS``, ``ERROR_ATTRIBUTES``, declared once in the bindings). The classes are also at the
top of ``vsinv``."""

from ._core import (
    ERROR_ATTRIBUTES,
    ERROR_CLASSES,
    ERROR_KINDS,
    DegenerateGeometry,
    InvalidInput,
    NotReady,
    VsinvError,
)

__all__ = [
    "ERROR_ATTRIBUTES",
    "ERROR_CLASSES",
    "ERROR_KINDS",
    "DegenerateGeometry",
    "InvalidInput",
    "NotReady",
    "VsinvError",
]
