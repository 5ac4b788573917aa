"""Independent fixed-interval RTS smoother (pykalman's KalmanFilter.smooth)
for tests/tests/smoother.rs: reads the fixture JSON that
nauta_tests::smoother_fixture writes ({"x0", "p0", "transitions": [{"phi",
"b", "q"}], "measurements": [{"h", "z", "r"} or null]}) and prints JSON
{"filtered_means", "filtered_covariances", "smoothed_means",
"smoothed_covariances"}, one entry per step."""

import json
import sys

import numpy as np
from pykalman import KalmanFilter

job = json.load(open(sys.argv[1]))
n = len(job["measurements"])
dim = len(job["x0"])
phi = np.array([t["phi"] for t in job["transitions"]])
b = np.array([t["b"] for t in job["transitions"]])
q = np.array([t["q"] for t in job["transitions"]])
h = np.zeros((n, 1, dim))
r = np.ones((n, 1, 1))
z = np.ma.masked_all((n, 1))
for i, m in enumerate(job["measurements"]):
    if m is not None:
        h[i] = np.array(m["h"])
        r[i] = m["r"]
        z[i, 0] = m["z"]

kf = KalmanFilter(
    transition_matrices=phi,
    transition_offsets=b,
    transition_covariance=q,
    observation_matrices=h,
    observation_covariance=r,
    initial_state_mean=np.array(job["x0"]),
    initial_state_covariance=np.array(job["p0"]),
)
filtered_means, filtered_covs = kf.filter(z)
smoothed_means, smoothed_covs = kf.smooth(z)
json.dump(
    {
        "filtered_means": filtered_means.tolist(),
        "filtered_covariances": filtered_covs.tolist(),
        "smoothed_means": smoothed_means.tolist(),
        "smoothed_covariances": smoothed_covs.tolist(),
    },
    sys.stdout,
)
