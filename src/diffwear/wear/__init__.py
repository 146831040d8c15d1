"""Wear: Archard's law, one-cycle wear increments, evolution over many cycles."""

from .archard import MM3_PER_NM, SLIP_RATE_WIDTH, ArchardWear

__all__ = ["MM3_PER_NM", "SLIP_RATE_WIDTH", "ArchardWear"]
