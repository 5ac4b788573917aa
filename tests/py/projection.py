"""Independent local tangent plane and radii of curvature (pymap3d) for
tests/tests/projection.rs: reads JSON {"origin": [lat, lon, h], "points":
[[lat, lon, h], ...], "lats": [...]} (degrees, metres) and prints JSON
{"ned": [[n, e, d], ...], "meridian": [...], "transverse": [...]}."""

import json
import sys

import pymap3d
from pymap3d import rcurve

job = json.load(open(sys.argv[1]))
lat0, lon0, h0 = job["origin"]
ell = pymap3d.Ellipsoid.from_name("wgs84")
ned = [list(pymap3d.geodetic2ned(lat, lon, h, lat0, lon0, h0, ell=ell, deg=True))
       for lat, lon, h in job["points"]]
meridian = [float(rcurve.meridian(lat, ell=ell, deg=True)) for lat in job["lats"]]
transverse = [float(rcurve.transverse(lat, ell=ell, deg=True)) for lat in job["lats"]]
json.dump({"ned": ned, "meridian": meridian, "transverse": transverse}, sys.stdout)
