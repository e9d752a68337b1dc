"""Pure numerics of writing: glyph sources -> strokes -> turning points -> minimum-jerk trajectory.

Nothing here performs I/O or imports another skyquill package (enforced by import-linter).
"""
