"""What limits 1 Hz dead reckoning on the A-KIT trajectories (Snapir AUV,
github ansfl/A-KIT, Cohen and Klein 2025; read from a local copy, never
committed): a DVL scale factor and yaw misalignment fitted to the reference
velocity, and a delay between the DVL's stamps and the reference attitude.

    python3 docs/analysis/akit_dvl_timing.py DATA_DIR [N ...]

DATA_DIR holds TrajectoryN/{DVL,GT}_trajectoryN.csv. The dead reckoning is
`nauta bench nav --akit`'s naive one: each DVL sample rotated by the
reference attitude (Euler angles interpolated at its stamp + delay) and held
until the next sample, on the plane at the first reference position (radii
at its latitude); the final error in % of the reference's horizontal path.
Needs numpy.
"""

import sys

import numpy as np

A = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)


def rot(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([
        [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
        [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
        [-sp, sr * cp, cr * cp],
    ])


def load(root, n):
    g = np.loadtxt(f"{root}/Trajectory{n}/GT_trajectory{n}.csv", delimiter=",", skiprows=1)
    d = np.loadtxt(f"{root}/Trajectory{n}/DVL_trajectory{n}.csv", delimiter=",", skiprows=1)
    return g, d


def dead_reckoning(g, d, delay_s=0.0, scale=1.0, misalignment_rad=0.0):
    lat0, lon0 = g[0, 2], g[0, 1]
    rn = A * (1 - E2) / (1 - E2 * np.sin(lat0) ** 2) ** 1.5
    re = A / np.sqrt(1 - E2 * np.sin(lat0) ** 2)
    ref_n = (g[:, 2] - lat0) * rn
    ref_e = (g[:, 1] - lon0) * re * np.cos(lat0)
    path = np.sum(np.hypot(np.diff(ref_n), np.diff(ref_e)))
    t, ang = g[:, 0], np.unwrap(g[:, 7:10], axis=0)
    m = rot(0.0, 0.0, misalignment_rad)
    n = e = 0.0
    for k in range(len(d) - 1):
        tq = d[k, 0] + delay_s
        v = rot(*[np.interp(tq, t, ang[:, i]) for i in range(3)]) @ (m @ (scale * d[k, 1:4]))
        dt = d[k + 1, 0] - d[k, 0]
        n += v[0] * dt
        e += v[1] * dt
    last = len(d) - 1
    return 100 * np.hypot(n - ref_n[last], e - ref_e[last]) / path


def fit_scale_misalignment(g, d):
    """Least squares of the reference's horizontal velocity against
    s·R(ψ)·C_nb·v_dvl (complex form: one scale and one angle)."""
    za = np.array([complex(*(rot(*g[k, 7:10]) @ d[k, 1:4])[:2]) for k in range(len(d))])
    zb = g[: len(d), 4] + 1j * g[: len(d), 5]
    c = np.vdot(za, zb) / np.vdot(za, za)
    return abs(c), np.angle(c)


def main():
    root = sys.argv[1]
    ns = [int(x) for x in sys.argv[2:]] or [1, 2, 3, 4]
    for n in ns:
        g, d = load(root, n)
        s, psi = fit_scale_misalignment(g, d)
        print(
            f"trajectory {n}: naive {dead_reckoning(g, d):.3f} %; fitted scale {s:.4f}, "
            f"misalignment {np.degrees(psi):+.3f} deg -> {dead_reckoning(g, d, 0.0, s, psi):.3f} %"
        )
    for delay in [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5]:
        errs = [dead_reckoning(*load(root, n), delay) for n in ns]
        print(f"DVL delay {delay:.2f} s: " + " / ".join(f"{x:.3f}" for x in errs) + f"  mean {np.mean(errs):.3f} %")


if __name__ == "__main__":
    main()
