"""Wear: Archard's law, one-cycle wear increments, evolution over many cycles."""

from .archard import MM3_PER_NM, SLIP_RATE_WIDTH, ArchardWear

__all__ = [
    "MM3_PER_NM", "SLIP_RATE_WIDTH", "ArchardWear",
    "CycleResult", "wear_cycle", "reset_wear", "JointsCycleResult", "wear_cycle_joints",
    "LifeResult", "cycles_to_limit", "AbstractWearModel", "Dynamic", "peak_depth",
    "STATUS_TEXT",
    "EvolutionResult", "evolve", "smooth_max", "worn_volume", "worn_mechanism", "WearLimitError",
    "Evolver", "ChunkedEvolution", "Checkpoint", "save_checkpoint", "load_checkpoint",
]

# cycle/evolution import the contact package, which itself imports
# `wear.archard`: load them lazily to keep the import graph acyclic.
_LAZY = {
    "CycleResult": "cycle", "wear_cycle": "cycle", "reset_wear": "cycle",
    "JointsCycleResult": "cycle", "wear_cycle_joints": "cycle",
    "LifeResult": "life", "cycles_to_limit": "model", "AbstractWearModel": "model",
    "Dynamic": "model", "peak_depth": "peak", "STATUS_TEXT": "status",
    "EvolutionResult": "evolution", "evolve": "evolution", "smooth_max": "evolution",
    "worn_volume": "evolution", "worn_mechanism": "evolution", "WearLimitError": "evolution",
    "Evolver": "evolution", "ChunkedEvolution": "evolution", "Checkpoint": "evolution",
    "save_checkpoint": "evolution", "load_checkpoint": "evolution",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(name)
