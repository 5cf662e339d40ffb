"""The verdict: the correct-model floor (over families of correct integrators), the residual test against it,
and the status the two ends of the ladder earn."""
