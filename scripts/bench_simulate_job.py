"""The whole `finrs simulate` job against the same job in numpy/scipy.

    python3 scripts/bench_simulate_job.py FINRS DIR [--scaling ROWS,ROWS,...]

DIR holds phi.txt, gamma.txt and c.txt (the discrete N = 3 strip that
model-core's bench_run example exports). Writes DIR/in.csv, a 20 s, 1 kHz,
3-segment recording (time, three drive voltages, three measured currents,
as the DAQ writes them), then times, in this one run:

  finrs  `FINRS simulate --input in.csv --out finrs.csv` as a whole process
         (start-up, reading, simulating, writing), wall and CPU time;
  scipy  numpy.loadtxt of in.csv, scipy.signal.dlsim of a state space of
         the same size (the same Φ and Γ, the tip row of C and four more
         output rows with feed-through, as many outputs as finrs writes),
         numpy.savetxt of time, voltages and the five outputs, measured
         inside Python after its imports (the conventional comparison),
         and also as a whole `python3 -c` process with its imports.

Prints medians over the repetitions and the ratio, and checks that both
give the same tip. With --scaling, then the same two jobs on recordings of
each number of rows (finrs median of 9, scipy after imports median of 3)
and what a row costs each beyond the smallest: how much of finrs's time
is fixed (start-up, files) and what ratio longer recordings tend to.
"""
import os
import statistics
import subprocess
import sys
import time

import numpy as np
from scipy import signal

REPS = 15
ROWS = 20_000
DT_S = 1e-3
META = """# format = "ipmc-bench/1"
# segments = 3
# length_m = 0.05
# width_m = 0.01
# thickness_m = 0.0002858
# sample = "bench"
# fixture = "free"
# medium = "air"
"""


def make_input(path, rows=ROWS):
    """A travelling 2.5 V, 1 Hz sine after a 1 s rest, with made-up
    currents; times to the ms, voltages to 0.1 mV, currents to 1 µA."""
    t = np.arange(rows) * DT_S
    phase = 2 * np.pi * (t[:, None] - 1.0) - np.arange(3)[None, :] * 2 * np.pi / 3
    v = np.where(t[:, None] >= 1.0, 2.5 * np.sin(phase), 0.0)
    rng = np.random.default_rng(15)
    i = v / 130.0 + 1e-4 * rng.standard_normal(v.shape)
    with open(path, "w") as f:
        f.write(META)
        f.write("t_s,v1_V,v2_V,v3_V,i1_A,i2_A,i3_A\n")
        for k in range(rows):
            f.write(
                f"{t[k]:.3f},{v[k, 0]:.4f},{v[k, 1]:.4f},{v[k, 2]:.4f},"
                f"{i[k, 0]:.6f},{i[k, 1]:.6f},{i[k, 2]:.6f}\n"
            )


def scipy_job(src, dst, system):
    """Read, simulate, write: what `finrs simulate` does, in numpy/scipy."""
    data = np.loadtxt(src, delimiter=",", skiprows=META.count("\n") + 1)
    t, u = data[:, 0], data[:, 1:4]
    _, y, _ = signal.dlsim(system, u)
    out = np.column_stack([t, u, y])
    np.savetxt(
        dst,
        out,
        delimiter=",",
        fmt=["%.17g"] * 4 + ["%.10f"] * y.shape[1],
        header=META + "t_s,v1_V,v2_V,v3_V,i1_A,i2_A,i3_A,tip_y_m,tip_x_m",
        comments="",
    )
    return y


def run_process(argv):
    """Wall seconds and CPU seconds (user + system) of one whole process."""
    start = time.perf_counter()
    pid = os.posix_spawn(
        argv[0],
        argv,
        os.environ,
        file_actions=[
            (os.POSIX_SPAWN_OPEN, 1, os.devnull, os.O_WRONLY, 0),
            (os.POSIX_SPAWN_OPEN, 2, os.devnull, os.O_WRONLY, 0),
        ],
    )
    _, status, usage = os.wait4(pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(argv)} failed")
    return wall, usage.ru_utime + usage.ru_stime


def timed_scipy(src, dst, system, reps):
    """Wall and CPU seconds of `reps` scipy jobs inside this process, and
    the outputs of the last."""
    runs = []
    for _ in range(reps):
        start, cpu = time.perf_counter(), time.process_time()
        y = scipy_job(src, dst, system)
        runs.append((time.perf_counter() - start, time.process_time() - cpu))
    return runs, y


def scaling(finrs, d, system, counts):
    """Both jobs on recordings of `counts` rows each; the ratios, and the
    cost of a row beyond the smallest recording."""
    print("rows      finrs ms   scipy ms   ratio")
    times = []
    for rows in counts:
        src = os.path.join(d, f"in-{rows}.csv")
        make_input(src, rows)
        argv = [finrs, "simulate", "--input", src, "--out", os.path.join(d, "finrs-n.csv")]
        fw = statistics.median(run_process(argv)[0] for _ in range(9))
        runs, _ = timed_scipy(src, os.path.join(d, "scipy-n.csv"), system, 3)
        sw = statistics.median(w for w, _ in runs)
        times.append((rows, fw, sw))
        print(f"{rows:7d} {fw * 1e3:10.2f} {sw * 1e3:10.1f} {sw / fw:7.1f}x", flush=True)
    (r0, f0, s0), (r1, f1, s1) = times[0], times[-1]
    if r1 > r0:
        fr, sr = (f1 - f0) / (r1 - r0), (s1 - s0) / (r1 - r0)
        print(f"a row beyond {r0}: finrs {fr * 1e9:.0f} ns, scipy {sr * 1e9:.0f} ns "
              f"(ratio {sr / fr:.1f}x); finrs fixed {(f0 - fr * r0) * 1e3:.2f} ms")


def main():
    finrs, d = sys.argv[1], sys.argv[2]
    counts = None
    if len(sys.argv) > 3:
        if len(sys.argv) != 5 or sys.argv[3] != "--scaling":
            sys.exit("usage: bench_simulate_job.py FINRS DIR [--scaling ROWS,ROWS,...]")
        try:
            counts = sorted(int(n) for n in sys.argv[4].split(","))
        except ValueError:
            sys.exit(f"--scaling: {sys.argv[4]!r} is not a comma-separated list of row counts")
        if not counts or counts[0] < 1:
            sys.exit("--scaling: row counts must be at least 1")
    src = os.path.join(d, "in.csv")
    make_input(src)
    phi = np.loadtxt(f"{d}/phi.txt")
    gamma = np.loadtxt(f"{d}/gamma.txt")
    c_tip = np.loadtxt(f"{d}/c.txt").reshape(1, -1)
    rng = np.random.default_rng(3)
    c = np.vstack([c_tip, rng.standard_normal((4, phi.shape[0]))])
    dd = np.vstack([np.zeros((1, 3)), rng.standard_normal((4, 3))])
    system = (phi, gamma, c, dd, DT_S)

    argv = [finrs, "simulate", "--input", src, "--out", os.path.join(d, "finrs.csv")]
    finrs_runs = [run_process(argv) for _ in range(REPS)]

    scipy_runs, y = timed_scipy(src, os.path.join(d, "scipy.csv"), system, REPS)
    # The same job as a whole process, imports included.
    npz = os.path.join(d, "system.npz")
    np.savez(npz, a=phi, b=gamma, c=c, d=dd)
    code = (
        f"import sys; sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r}); "
        "import numpy as np; import bench_simulate_job as b; "
        f"s = np.load({npz!r}); "
        f"b.scipy_job({src!r}, {os.path.join(d, 'scipy2.csv')!r}, "
        "(s['a'], s['b'], s['c'], s['d'], b.DT_S))"
    )
    whole = [run_process([sys.executable, "-c", code]) for _ in range(5)]

    ours = np.loadtxt(
        os.path.join(d, "finrs.csv"), delimiter=",", skiprows=META.count("\n") + 2
    )
    diff = float(np.max(np.abs(ours[:, 7] - y[:, 0])))

    fw = statistics.median(w for w, _ in finrs_runs)
    fc = statistics.median(c for _, c in finrs_runs)
    sw = statistics.median(w for w, _ in scipy_runs)
    sc = statistics.median(c for _, c in scipy_runs)
    pw = statistics.median(w for w, _ in whole)
    sizes = [os.path.getsize(os.path.join(d, n)) for n in ("in.csv", "finrs.csv", "scipy.csv")]
    print(f"job: read a 20 s, 1 kHz, N = 3 recording ({ROWS} rows, {sizes[0] / 1e6:.2f} MB), simulate, write")
    print(f"finrs simulate, whole process:  {fw * 1e3:7.2f} ms wall, {fc * 1e3:6.2f} ms CPU (median of {REPS}; {sizes[1] / 1e6:.2f} MB out)")
    print(f"scipy job, after imports:       {sw * 1e3:7.2f} ms wall, {sc * 1e3:6.2f} ms CPU (median of {REPS}; loadtxt, dlsim, savetxt; {sizes[2] / 1e6:.2f} MB out)")
    print(f"scipy job, whole python3 process: {pw * 1e3:7.2f} ms wall (median of {len(whole)}, imports included)")
    print(f"numpy {np.__version__}, scipy {__import__('scipy').__version__}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print(f"ratio (scipy job after imports / finrs process): {sw / fw:6.1f}x wall, {sc / fc:6.1f}x CPU")
    print(f"ratio (whole processes):                         {pw / fw:6.1f}x")
    print(f"largest tip difference: {diff:.3e} m")
    if not diff < 1e-9:
        sys.exit("the two simulations disagree")
    if counts:
        scaling(finrs, d, system, counts)


if __name__ == "__main__":
    main()
