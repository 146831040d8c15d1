"""Exceptions users can catch, and the CLI's exit codes for them.

``InputError`` (exit code 2): the model or its input is wrong; the message names
the file / key / value and the allowed range.  ``SolverError`` (exit code 3): the
model was accepted but the numerical solution failed (step limit, NaN, no
convergence); the message names the stage and the simulated time.
``OutputError`` (exit code 4): the results could not be written (a full disk).
"""

from __future__ import annotations


class DiffwearError(Exception):
    """Base class of every error diffwear raises on purpose."""

    exit_code = 1


class InputError(DiffwearError, ValueError):
    """Bad input: a parameter, a file or a model description that cannot be used."""

    exit_code = 2


class OutputError(DiffwearError, OSError):
    """Results could not be written (a full disk, a folder that became
    unwritable); the message names the file and the folder."""

    exit_code = 4


class SolverError(DiffwearError, RuntimeError):
    """A numerical failure: the integrator or a nonlinear solve did not succeed."""

    exit_code = 3
