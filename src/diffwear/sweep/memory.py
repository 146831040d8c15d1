"""How many points of a sweep fit in memory at once.

A vmapped model holds every point's working arrays together: a 100,000-point
quasi-static sweep asked one program for 48 GB and died with XLA's
``RESOURCE_EXHAUSTED``.  `chunk_for_memory` compiles the batched model at the
chunk asked for (no memory is taken until it runs), reads XLA's own account
of the program's memory (`jax.stages.Compiled.memory_analysis`: arguments,
outputs and temporaries), takes it as linear in the batch (vmap stacks every
array along the batch), and where it does not fit in `MEMORY_SHARE` of the
memory available (the device's limit on an accelerator, ``MemAvailable`` of the
host on a CPU) uses the largest chunk that does (compiled again).  A
requested chunk that does not fit, or a single point that does not, is an
`InputError` with the estimate.
"""

from __future__ import annotations

import math
import os

from ..errors import InputError

MEMORY_SHARE = 0.5   # of the available memory one chunk may use (room for the rest)


def available_bytes(device) -> float:
    """Memory one program may use on ``device``: its allocator's limit on an
    accelerator, the host's available memory on a CPU (inf if unknown)."""
    if device.platform != "cpu":
        stats = device.memory_stats() or {}
        limit = stats.get("bytes_limit")
        if limit:
            return float(limit) - float(stats.get("bytes_in_use", 0))
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return math.inf


def program_bytes(compiled) -> float:
    """Arguments + outputs + temporaries of a compiled program (XLA's count;
    0 where the backend gives none)."""
    try:
        m = compiled.memory_analysis()
    except Exception:  # noqa: BLE001 - a backend without the analysis: no estimate
        return 0.0
    if m is None:
        return 0.0
    return float(m.argument_size_in_bytes + m.output_size_in_bytes + m.temp_size_in_bytes)


def chunk_for_memory(compile_at, n: int, n_devices: int, requested: int | None, device):
    """(chunk size, bytes per point, the program compiled at that size or None).

    ``compile_at(size)`` compiles the batched model for ``size`` points (no
    memory is taken until it runs).  It is compiled at the chunk asked for
    (``requested``, or all ``n`` points); if that does not fit, a requested
    chunk is refused, and the default becomes the largest that fits (the
    caller compiles it).  Sizes are multiples of ``n_devices``."""
    size = n_devices * math.ceil(min(int(requested or n), n) / n_devices)
    compiled = compile_at(size)
    per_point = program_bytes(compiled) / size
    budget = MEMORY_SHARE * available_bytes(device) * n_devices
    fits = math.inf if per_point <= 0 else budget / per_point
    if fits < n_devices:
        raise InputError(
            f"sweep: one point of this model needs ~{per_point / 1e9:.3g} GB (XLA's "
            f"estimate), more than the {budget / 1e9:.3g} GB available; allowed: a coarser "
            "model (fewer profile nodes or load samples)")
    if size <= fits:
        return size, per_point, compiled
    most = int(n_devices * (fits // n_devices))
    if requested is not None:
        raise InputError(
            f"sweep: chunk_size {size} needs ~{size * per_point / 1e9:.3g} GB "
            f"(~{per_point / 1e6:.3g} MB a point, XLA's estimate), more than the "
            f"{budget / 1e9:.3g} GB available; allowed: chunk_size <= {most}")
    return most, per_point, None
