"""Heads a user brings: instrumenting a mesh nobody measured (landmarks, size, axes, unit)."""
