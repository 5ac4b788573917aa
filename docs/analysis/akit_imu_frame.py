"""The A-KIT IMU files (Snapir AUV, github ansfl/A-KIT at commit c2168ed,
Cohen and Klein 2025; read from a local copy, never committed): their time
base, axes and units against the reference (GT_trajectoryN.csv of the
repository's head).

    python3 docs/analysis/akit_imu_frame.py DATA_DIR [N ...]

DATA_DIR holds TrajectoryN/{GT,IMU}_trajectoryN.csv. Needs numpy.

1. Time base: the gyro Z angle over each reference interval against the
   reference's yaw increment, for a map t_ref = a * t_imu + b fitted by grid
   search (and b alone, a = 1, per 40 s window: the drift that shows a).
2. Axes and signs, on that time base, per reference interval: gyro X, Y, Z
   against the body rates of the reference's attitude increments (p, q, r,
   FRD); accelerometer X against the forward acceleration du/dt and
   g sin(pitch), accelerometer Y against the centripetal u r and
   g sin(roll) (FRD specific force: f_x = du/dt + g sin(theta),
   f_y = u r - g sin(phi) for small angles). A coefficient near -1 is an
   axis of the opposite sense.
3. What is left once Y is negated: the mean gyro and accelerometer residual
   against the reference (biases) and the sample-to-sample noise.
"""

import sys

import numpy as np

from akit_dvl_timing import rot  # the attitude matrix C_nb (FRD to NED)

G = 9.795


def log_so3(m):
    c = np.clip((np.trace(m) - 1) / 2, -1, 1)
    a = np.arccos(c)
    w = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]) / 2
    return w if a < 1e-9 else w * a / np.sin(a)


def load(root, n):
    g = np.loadtxt(f"{root}/Trajectory{n}/GT_trajectory{n}.csv", delimiter=",", skiprows=1)
    imu = np.loadtxt(f"{root}/Trajectory{n}/IMU_trajectory{n}.csv", delimiter=",", skiprows=1)
    return g, imu


def increments(t_ref, t_imu, x):
    """The integral of x (sampled at t_imu, held forward) over each
    reference interval."""
    c = np.concatenate([[0.0], np.cumsum(x[:-1] * np.diff(t_imu))])
    return np.diff(np.interp(t_ref, t_imu, c))


def inside(t_ref, t_imu):
    ok = (t_ref > t_imu[0]) & (t_ref < t_imu[-1])
    return ok[1:] & ok[:-1]


def yaw_residual(g, imu, a, b, sl=slice(None)):
    t = a * imu[:, 0] + b
    ok = inside(g[:, 0], t)
    d = increments(g[:, 0], t, imu[:, 6]) - np.diff(np.unwrap(g[:, 9]))
    return np.sqrt(np.mean(d[sl][ok[sl]] ** 2))


def fit_time(g, imu):
    best = (np.inf, 1.0, 0.0)
    for a in np.arange(0.9990, 1.0050, 0.00025):
        for b in np.arange(-0.5, 2.0, 0.02):
            r = yaw_residual(g, imu, a, b)
            if r < best[0]:
                best = (r, a, b)
    return best


def window_offsets(g, imu):
    out = []
    for w0 in range(10, 390, 60):
        sl = slice(w0, w0 + 40)
        bs = np.arange(-0.5, 2.5, 0.02)
        r = [yaw_residual(g, imu, 1.0, b, sl) for b in bs]
        out.append((g[w0 + 20, 0], bs[int(np.argmin(r))]))
    return out


def regressions(g, imu, a, b):
    t_ref = g[:, 0]
    t = a * imu[:, 0] + b
    ok = inside(t_ref, t)
    dt = np.diff(t_ref)
    mean = [increments(t_ref, t, imu[:, i]) / dt for i in range(1, 7)]
    c = [rot(*e) for e in g[:, 7:10]]
    w = np.array([log_so3(c[k].T @ c[k + 1]) for k in range(len(c) - 1)]) / dt[:, None]
    psi = np.unwrap(g[:, 9])
    u = np.cos(psi) * g[:, 4] + np.sin(psi) * g[:, 5]
    mid = lambda x: (x[1:] + x[:-1]) / 2
    du = np.diff(u) / dt
    ur = mid(u) * np.diff(psi) / dt
    gth = G * np.sin(mid(g[:, 8]))
    gph = G * np.sin(mid(g[:, 7]))

    def ls(y, *cols):
        m = np.column_stack(list(cols) + [np.ones_like(y)])[ok]
        s, *_ = np.linalg.lstsq(m, y[ok], rcond=None)
        return s

    res = {
        "gyro X ~ p": ls(mean[3], w[:, 0])[0],
        "gyro Y ~ q": ls(mean[4], w[:, 1])[0],
        "gyro Z ~ r": ls(mean[5], w[:, 2])[0],
    }
    s = ls(mean[0], du, gth)
    res["acc X ~ du/dt"], res["acc X ~ g sin(theta)"] = s[0], s[1]
    s = ls(mean[1], ur, gph)
    res["acc Y ~ u r"], res["acc Y ~ -g sin(phi)"] = s[0], -s[1]
    # After negating Y: the mean residual against the reference (biases).
    f_ref = np.array([c[k].T @ (np.array([0, 0, -G]) + (g[k + 1, 4:7] - g[k, 4:7]) / dt[k]) for k in range(len(dt))])
    sign = np.array([1, -1, 1])
    gyro = np.column_stack(mean[3:6]) * sign
    acc = np.column_stack(mean[0:3]) * sign
    bias_g = np.mean((gyro - w)[ok], axis=0)
    bias_a = np.mean((acc - f_ref)[ok], axis=0)
    noise_g = np.std(np.diff(imu[:, 4:7], axis=0), axis=0) / np.sqrt(2)
    noise_a = np.std(np.diff(imu[:, 1:4], axis=0), axis=0) / np.sqrt(2)
    return res, bias_g, bias_a, noise_g, noise_a


def main():
    root = sys.argv[1]
    ns = [int(x) for x in sys.argv[2:]] or [1, 2, 3, 4]
    for n in ns:
        g, imu = load(root, n)
        r, a, b = fit_time(g, imu)
        print(f"trajectory {n}: t_ref = {a:.5f} t_imu {b:+.2f} s (yaw residual {r * 1e3:.2f} mrad per interval; "
              f"with t_ref = t_imu: {yaw_residual(g, imu, 1.0, 0.0) * 1e3:.2f}); reference spacing {g[1, 0] - g[0, 0]:.5f} s, "
              f"IMU spacing {imu[1, 0] - imu[0, 0]:.7f} s")
        print("  offset per 40 s window (a = 1): " + ", ".join(f"{t:.0f} s: {o:+.2f}" for t, o in window_offsets(g, imu)))
        res, bg, ba, ng, na = regressions(g, imu, a, b)
        print("  " + ", ".join(f"{k} {v:+.2f}" for k, v in res.items()))
        print(f"  Y negated: gyro bias {np.round(bg * 1e3, 2)} mrad/s, accelerometer bias {np.round(ba, 3)} m/s^2, "
              f"noise per sample gyro {np.round(ng * 1e3, 2)} mrad/s, accelerometer {np.round(na, 3)} m/s^2")


if __name__ == "__main__":
    main()
