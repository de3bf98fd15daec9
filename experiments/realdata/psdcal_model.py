"""psdcal's measured -> ray map (docs/model.md §2-3, §3.3), written out from
the documented equations to judge calibration.json files from Python:
psd_radial (l1, l2 about the electrical centre) -> aspect (y' = cy + (y - cy)/(1 + a))
-> lens (k1, k2, k3, p1, p2 about (cx, cy)) -> pinhole (f, skew)."""

import json

import numpy as np


def load(path):
    with open(path) as f:
        c = json.load(f)
    p = dict(c["parameters"])
    p.setdefault("a", 0.0)
    return p, c


def ray(p, m):
    """Normalised rays (a, b) of measured points m (N x 2, mm)."""
    x, y = m[:, 0].copy(), m[:, 1].copy()
    h2 = x * x + y * y
    s = 1 + h2 * (p["l1"] + h2 * p["l2"])
    x, y = x * s, y * s
    y = p["cy"] + (y - p["cy"]) / (1 + p["a"])
    dx, dy = x - p["cx"], y - p["cy"]
    r2 = dx * dx + dy * dy
    rho = r2 * (p["k1"] + r2 * (p["k2"] + r2 * p["k3"]))
    tx = p["p1"] * (r2 + 2 * dx * dx) + 2 * p["p2"] * dx * dy
    ty = p["p2"] * (r2 + 2 * dy * dy) + 2 * p["p1"] * dx * dy
    xi, yi = x + dx * rho + tx, y + dy * rho + ty
    b = (yi - p["cy"]) / p["f"]
    a = (xi - p["cx"] - p["skew"] * b) / p["f"]
    return np.stack([a, b], axis=1)


def angles_deg(r1, r2):
    """Angles between the rays (a, b, 1) of two N x 2 arrays, degrees."""
    u = np.column_stack([r1, np.ones(len(r1))])
    v = np.column_stack([r2, np.ones(len(r2))])
    cross = np.linalg.norm(np.cross(u, v), axis=1)
    dot = np.sum(u * v, axis=1)
    return np.degrees(np.arctan2(cross, dot))


def truth_parameters(truth_json):
    """The parameters of a simulator's truth.json (psdcal-truth, standard model)."""
    with open(truth_json) as f:
        t = json.load(f)
    i = t["intrinsics"]
    return {"f": i["f_mm"], "cx": i["cx_mm"], "cy": i["cy_mm"], "skew": i["skew"], "a": 0.0,
            **t["distortion"]}


def aoa_rms_deg(est, truth, half=4.5, n=41):
    """RMS angle between the estimated and the true rays over an n x n grid of
    measured points on the active area (+-half mm)."""
    g = np.linspace(-half, half, n)
    m = np.array([(x, y) for x in g for y in g])
    return float(np.sqrt(np.mean(angles_deg(ray(est, m), ray(truth, m)) ** 2)))
