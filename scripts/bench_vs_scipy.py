"""Times scipy.signal.dlsim on the system finrs exported, checks that both
give the same tip, and prints both times and the ratio."""
import sys
import time

import numpy as np
from scipy import signal

d = sys.argv[1]
finrs_ns = float(sys.argv[2])
phi = np.loadtxt(f"{d}/phi.txt")
gamma = np.loadtxt(f"{d}/gamma.txt")
c = np.loadtxt(f"{d}/c.txt").reshape(1, -1)
u = np.loadtxt(f"{d}/input.txt")
ours = np.loadtxt(f"{d}/tip_finrs.txt")
system = (phi, gamma, c, np.zeros((1, 3)), 1e-3)
best = float("inf")
for _ in range(5):
    start = time.perf_counter()
    _, y, _ = signal.dlsim(system, u)
    best = min(best, time.perf_counter() - start)
scipy_ns = best / len(u) * 1e9
diff = float(np.max(np.abs(y[:, 0] - ours)))
print(f"run: 20 s at 1 kHz, N = 3, f64 ({len(u)} steps)")
print(f"finrs: {finrs_ns:10.1f} ns/step")
print(f"scipy: {scipy_ns:10.1f} ns/step (signal.dlsim, scipy {__import__('scipy').__version__})")
print(f"ratio: {scipy_ns / finrs_ns:10.0f}x")
print(f"largest tip difference: {diff:.3e} m")
if not diff < 1e-9:
    sys.exit("the two simulations disagree")
