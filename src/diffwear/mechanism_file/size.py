"""What a mechanism file will cost before it is traced: a compile-time and
memory estimate from its size, a warning when the wait is long, a refusal
when the memory cannot be had.

The traced program grows with every joint and force element (each is its own
piece of the constraint and force functions, compiled unrolled) and with the
coordinates; the command's time and peak memory were measured on files of
free bodies and of pendulum chains (``benchmarks/compile_size.py``, record
``benchmarks/records/compile_size.json``) and fitted as

    seconds = a + b elements + c coordinates
    memory  = a + b elements^2 + c coordinates

which the coefficients below copy.  The time is that of a 2-core machine;
faster machines take less, so a long estimate is a warning with a progress
line while it compiles (nothing looks hung: `diffwear.progress`), and beyond
the compile budget a question: the command runs it with ``--yes`` only.  The memory estimate is a
refusal where the machine has less.
"""

from __future__ import annotations

import os
from typing import NamedTuple

from ..config import MechanismFile
from ..errors import InputError
from ..progress import minutes

# Fit of benchmarks/records/compile_size.json: `diffwear run FILE` in a fresh
# process (start-up, compilation, a 0.01 s run), 2-core x86-64 machine.
SECONDS_BASE = 1.3489027634987505
SECONDS_PER_ELEMENT = 0.39739443497453725
SECONDS_PER_COORDINATE = 0.006435270778763141
BYTES_BASE = 488173449.4486675
BYTES_PER_ELEMENT_SQUARED = 132248.11285424372
BYTES_PER_COORDINATE = 90094.8726219042

# A wait worth saying before it starts (and a progress line through it).
WARN_SECONDS = 60.0
# The compile budget: an estimate beyond it runs only when asked for (--yes).
# Ten minutes: the 10,000 free bodies a hostile-input trial ran (about 3 min,
# 3.2 GB) stay within it; a 1,500-link chain (about 10 min) does not.
COMPILE_BUDGET_SECONDS = 600.0


class SizeEstimate(NamedTuple):
    """A mechanism's size and what compiling and running it is estimated to take."""

    bodies: int
    elements: int       # joints (drivers included) and force elements
    coordinates: int
    seconds: float
    bytes: float

    def describe(self) -> str:
        return (f"{self.bodies:,} bodies, {self.elements:,} joints and force elements "
                f"({self.coordinates:,} coordinates)")


def estimate(mfile: MechanismFile) -> SizeEstimate:
    """The file's size, and the fit's time and peak memory for it."""
    mech = mfile.mechanism
    elements = len(mech.constraints) + len(mech.forces)
    coordinates = mech.n_coords
    seconds = SECONDS_BASE + SECONDS_PER_ELEMENT * elements + SECONDS_PER_COORDINATE * coordinates
    memory = (BYTES_BASE + BYTES_PER_ELEMENT_SQUARED * elements ** 2
              + BYTES_PER_COORDINATE * coordinates)
    return SizeEstimate(len(mech.bodies), elements, coordinates, seconds, memory)


def physical_memory() -> int | None:
    """This machine's memory in bytes (None where the platform does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def check_size(mfile: MechanismFile, memory: int | None = None, *, yes: bool = True
               ) -> str | None:
    """Refuse (`InputError`) a file whose estimated memory exceeds ``memory``
    (default: this machine's), and, unless ``yes``, one whose estimated
    compile exceeds `COMPILE_BUDGET_SECONDS`; return a warning when its
    estimated time passes `WARN_SECONDS`, else None."""
    est = estimate(mfile)
    memory = physical_memory() if memory is None else memory
    if memory is not None and est.bytes > memory:
        raise InputError(
            f"{mfile.file}: {est.describe()}: compiling and running it needs an estimated "
            f"{est.bytes / 1e9:.1f} GB of memory, more than this machine's "
            f"{memory / 1e9:.1f} GB; allowed: a mechanism whose estimate fits (fewer joints, "
            "force elements or bodies), or a machine with more memory")
    if est.seconds > COMPILE_BUDGET_SECONDS and not yes:
        raise InputError(
            f"{mfile.file}: {est.describe()}: compiling it is estimated to take about "
            f"{minutes(est.seconds)} and {est.bytes / 1e9:.1f} GB of memory on a 2-core "
            f"machine, beyond the compile budget of {minutes(COMPILE_BUDGET_SECONDS)}; "
            "allowed: --yes to run it anyway (a progress line shows the compile; Ctrl-C "
            "stops it cleanly), or a mechanism with fewer joints, force elements or bodies")
    if est.seconds > WARN_SECONDS:
        return (f"{mfile.file}: {est.describe()}: compiling it is estimated to take about "
                f"{est.seconds / 60:.0f} min and {est.bytes / 1e9:.1f} GB of memory on a 2-core "
                "machine (the time grows with each joint, force element and coordinate); "
                "Ctrl-C stops it cleanly")
    return None


__all__ = ["COMPILE_BUDGET_SECONDS", "SizeEstimate", "check_size", "estimate",
           "physical_memory"]
