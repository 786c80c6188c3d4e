"""Structural analysis: place and transition invariants, siphons and traps."""
