"""One vehicle: take a job, lay the glyph on the board, plan, fly the control loop, report."""
