"""Sim-to-real gap diagnosis: where a current model's gap lies, which unmodelled effect causes it, how far it shrinks."""

__all__: list[str] = []
