"""Wilson's 95 % interval for a proportion, shared by the scripts that
tally sweeps (right-by-strength, coverage-bounded); the rig's own is
`finrs_rig::sweep::wilson`."""
import math


def wilson(k, n, z=1.959964):
    """(low, high) of the proportion k/n; (0, 1) for n = 0."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))
