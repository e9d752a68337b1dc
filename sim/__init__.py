"""The simulated world that replaces hardware: vehicles, inner loops, wind, mocap, boards, ink.

Pure stepping functions; no transport inside a physics step (enforced by import-linter).
"""
