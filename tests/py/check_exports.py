"""Independent checks of `nauta export` outputs (tests/tests/export.rs).

    check_exports.py FORMAT OUT EXPECT_JSON

FORMAT is kml, geojson, gpx, csv or foxglove; EXPECT_JSON is written by the
Rust test: the source recording, its per-topic message counts, the tracks, the
first truth position, the buoy and transponder points. Prints `ok FORMAT ...`
and exits 0 when OUT passes, raises (exit 1) otherwise.

The readers are not nauta's: xml.etree and the OGC KML 2.2 XML Schema shipped
with fastkml (validated with lxml); the GeoJSON JSON Schema of geojson-pydantic
(validated with jsonschema), geojson-pydantic's models and the `geojson`
package, plus RFC 7946's own rules; gpxpy and the GPX 1.1 element order;
Python's csv module; the PyPI `mcap` reader and jsonschema.
"""

import csv
import json
import math
import pathlib
import sys
import xml.etree.ElementTree as ET
from collections import Counter, defaultdict

TOL_DEG = 1e-7


def fail(msg):
    raise AssertionError(msg)


def check(cond, msg):
    if not cond:
        fail(msg)


def near(a, b, tol=TOL_DEG):
    return abs(float(a) - float(b)) <= tol


# --------------------------------------------------------------------------- KML

KML_NS = "{http://www.opengis.net/kml/2.2}"


def check_kml(path, exp):
    from fastkml import validator

    # The OGC KML 2.2 schema (fastkml ships it and its imports).
    valid = validator.validate(file_to_validate=pathlib.Path(path))
    check(valid is True, "the KML schema could not be loaded (is lxml installed?)")
    root = ET.parse(path).getroot()
    check(root.tag == KML_NS + "kml", f"root is {root.tag}")
    doc = root.find(KML_NS + "Document")
    check(doc is not None, "no Document")
    folders = {f.findtext(KML_NS + "name"): f for f in doc.findall(KML_NS + "Folder")}
    tracks = folders.get("Tracks")
    check(tracks is not None, f"no Tracks folder: {list(folders)}")
    lines = {}
    for pm in tracks.findall(KML_NS + "Placemark"):
        name = pm.findtext(KML_NS + "name")
        ls = pm.findall(".//" + KML_NS + "LineString")
        check(len(ls) == 1, f"{name}: {len(ls)} LineStrings")
        check(name not in lines, f"{name} twice")
        coords = ls[0].findtext(KML_NS + "coordinates").split()
        check(len(coords) >= 2, f"{name}: {len(coords)} coordinates")
        lines[name] = [tuple(float(x) for x in c.split(",")) for c in coords]
        style = pm.findtext(KML_NS + "styleUrl")
        check(style and style.startswith("#"), f"{name}: no style")
        mode = ls[0].findtext(KML_NS + "altitudeMode")
        check(mode in ("clampToGround", "absolute"), f"{name}: altitudeMode {mode}")
    all_lines = root.findall(".//" + KML_NS + "LineString")
    check(len(all_lines) == len(exp["tracks"]), f"{len(all_lines)} LineStrings in the file")
    check(sorted(lines) == sorted(exp["tracks"]), f"tracks {sorted(lines)} != {sorted(exp['tracks'])}")
    for name, pts in lines.items():
        for lon, lat, _alt in pts:
            check(-180 <= lon <= 180 and -90 <= lat <= 90, f"{name}: bad point {lon},{lat}")
    kp = exp["known_point"]
    lon, lat, alt = lines[kp["topic"]][0]
    check(near(lon, kp["lon_deg"]) and near(lat, kp["lat_deg"]),
          f"first {kp['topic']} point {lon},{lat} != {kp['lon_deg']},{kp['lat_deg']} (lon,lat)")
    gps = [f for n, f in folders.items() if n and n.startswith("GPS fixes")]
    check(len(gps) == 1, f"GPS folders {list(folders)}")
    n_gps = len(gps[0].findall(KML_NS + "Placemark"))
    check(n_gps == len(lines["sensor/gps"]), f"{n_gps} GPS points, {len(lines['sensor/gps'])} in its line")
    buoy = folders.get("Buoy")
    check(buoy is not None and len(buoy.findall(KML_NS + "Placemark")) == exp["buoy_points"], "buoy points")
    tp = folders.get("LBL transponders")
    check(tp is not None, "no transponder folder")
    check_transponders(
        exp,
        {
            pm.findtext(KML_NS + "name"): tuple(
                float(x) for x in pm.findtext(".//" + KML_NS + "coordinates").split(",")[:2]
            )
            for pm in tp.findall(KML_NS + "Placemark")
        },
    )
    return f"{len(lines)} tracks, {n_gps} GPS fixes"


def check_transponders(exp, found):
    """found: name -> (lon, lat)."""
    check(len(found) == len(exp["transponders"]), f"transponders {found}")
    for t in exp["transponders"]:
        lon, lat = found[f"transponder {t['id']}"]
        check(near(lon, t["lon_deg"]) and near(lat, t["lat_deg"]), f"transponder {t['id']} at {lon},{lat}")


# ----------------------------------------------------------------------- GeoJSON


def check_geojson(path, exp):
    import geojson
    import jsonschema
    from geojson_pydantic import FeatureCollection

    text = pathlib.Path(path).read_text()
    doc = json.loads(text)
    # A GeoJSON JSON Schema (geojson-pydantic's models), then the models themselves.
    jsonschema.Draft202012Validator(FeatureCollection.model_json_schema()).validate(doc)
    FeatureCollection.model_validate(doc)
    gj = geojson.loads(text)
    check(gj.is_valid, f"geojson: {gj.errors()}")
    # RFC 7946 rules the schemas do not state.
    check(doc["type"] == "FeatureCollection", "not a FeatureCollection")
    check("crs" not in doc, "RFC 7946 has no crs member")

    def positions(geom):
        t, c = geom["type"], geom["coordinates"]
        return [c] if t == "Point" else c

    lines = {}
    points = Counter()
    for f in doc["features"]:
        g = f["geometry"]
        for p in positions(g):
            check(2 <= len(p) <= 3, f"position {p}")
            check(-180 <= p[0] <= 180 and -90 <= p[1] <= 90, f"position {p} out of range (lon, lat)")
        props = f["properties"]
        if g["type"] == "LineString":
            check(len(g["coordinates"]) >= 2, "a LineString needs two positions")
            topic = props["topic"]
            check(topic not in lines, f"{topic} twice")
            check(props["kind"] == "track", props)
            lines[topic] = g["coordinates"]
        else:
            check(g["type"] == "Point", g["type"])
            points[props["kind"]] += 1
    check(sorted(lines) == sorted(exp["tracks"]), f"LineString tracks {sorted(lines)}")
    kp = exp["known_point"]
    lon, lat = lines[kp["topic"]][0][:2]
    check(near(lon, kp["lon_deg"]) and near(lat, kp["lat_deg"]),
          f"first {kp['topic']} position [{lon}, {lat}] is not [lon, lat] = [{kp['lon_deg']}, {kp['lat_deg']}]")
    check(points["buoy"] == exp["buoy_points"], f"buoy points {points}")
    check_transponders(
        exp,
        {
            f["properties"]["name"]: tuple(f["geometry"]["coordinates"][:2])
            for f in doc["features"]
            if f["properties"].get("kind") == "transponder"
        },
    )
    # The synthetic ains/nav is north-east of the truth: both its latitude
    # and its longitude are larger at the start.
    nav0, truth0 = lines["ains/nav"][0], lines["sim/truth"][0]
    check(nav0[1] > truth0[1] and nav0[0] > truth0[0], f"nav {nav0} vs truth {truth0}")
    return ", ".join(f"{t} {len(c)} points" for t, c in sorted(lines.items()))


# --------------------------------------------------------------------------- GPX

GPX_NS = "{http://www.topografix.com/GPX/1/1}"
# GPX 1.1 (gpx.xsd) sequences, as element name -> allowed children in order.
GPX_ORDER = {
    "gpx": ["metadata", "wpt", "rte", "trk", "extensions"],
    "metadata": ["name", "desc", "author", "copyright", "link", "time", "keywords", "bounds", "extensions"],
    "wpt": ["ele", "time", "magvar", "geoidheight", "name", "cmt", "desc", "src", "link", "sym", "type",
            "fix", "sat", "hdop", "vdop", "pdop", "ageofdgpsdata", "dgpsid", "extensions"],
    "trk": ["name", "cmt", "desc", "src", "link", "number", "type", "extensions", "trkseg"],
    "trkseg": ["trkpt", "extensions"],
}
GPX_ORDER["trkpt"] = GPX_ORDER["wpt"]
GPX_ONCE = {"metadata", "ele", "time", "name", "desc", "type", "extensions"}


def check_gpx_order(el):
    tag = el.tag.replace(GPX_NS, "")
    order = GPX_ORDER.get(tag)
    if order is None:
        return
    last = -1
    seen = Counter()
    for child in el:
        check(child.tag.startswith(GPX_NS), f"{child.tag} outside the GPX namespace")
        name = child.tag.replace(GPX_NS, "")
        check(name in order, f"<{name}> not allowed in <{tag}>")
        i = order.index(name)
        check(i >= last, f"<{name}> out of order in <{tag}>")
        last = i
        seen[name] += 1
        if name in GPX_ONCE:
            check(seen[name] == 1, f"<{name}> twice in <{tag}>")
        check_gpx_order(child)
    if tag in ("wpt", "trkpt"):
        lat, lon = float(el.get("lat")), float(el.get("lon"))
        check(-90 <= lat <= 90 and -180 <= lon < 180, f"{tag} at {lat},{lon}")


def check_gpx(path, exp):
    import gpxpy

    root = ET.parse(path).getroot()
    check(root.tag == GPX_NS + "gpx" and root.get("version") == "1.1", f"{root.tag} {root.attrib}")
    check(root.get("creator"), "creator is required")
    check_gpx_order(root)
    with open(path) as f:
        g = gpxpy.parse(f)
    check(g.version == "1.1", g.version)
    names = [t.name for t in g.tracks]
    check(sorted(names) == sorted(exp["tracks"]), f"trk names {names}")
    check(len(root.findall(GPX_NS + "trk")) == len(exp["tracks"]), "one trk per track")
    tracks = {t.name: t for t in g.tracks}
    kp = exp["known_point"]
    p0 = tracks[kp["topic"]].segments[0].points[0]
    check(near(p0.latitude, kp["lat_deg"]) and near(p0.longitude, kp["lon_deg"]), f"first point {p0}")
    points = [p for t in g.tracks for s in t.segments for p in s.points]
    timed = [p.time is not None for p in points]
    check(all(timed) or not any(timed), "some points have a time, some not")
    if all(timed):
        for t in g.tracks:
            for s in t.segments:
                times = [p.time for p in s.points]
                check(times == sorted(times), f"{t.name}: times go back")
    # Depth streams carry ele = -depth (<= 0 below the surface).
    truth = [p for s in tracks["sim/truth"].segments for p in s.points]
    check(all(p.elevation is not None and p.elevation <= 1e-9 for p in truth), "truth ele")
    check(all(p.elevation is None for s in tracks["sensor/gps"].segments for p in s.points), "gps ele")
    wpts = Counter(w.type for w in g.waypoints)
    check(wpts["buoy"] == exp["buoy_points"], f"waypoints {wpts}")
    check_transponders(
        exp, {w.name: (w.longitude, w.latitude) for w in g.waypoints if w.type == "transponder"}
    )
    return f"{len(g.tracks)} trk, {len(points)} points, times {'yes' if all(timed) else 'no'}"


# --------------------------------------------------------------------------- CSV


def check_csv(path, exp):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    check(header == exp["csv_header"].split(","), f"header {header}")
    body = [dict(zip(header, r)) for r in rows[1:]]
    check(all(len(r) == len(header) for r in rows), "ragged rows")
    counts = Counter(r["topic"] for r in body)
    check(dict(counts) == exp["csv_counts"], f"row counts {dict(counts)} != {exp['csv_counts']}")
    for r in body:
        for k, v in r.items():
            if k not in ("topic", "type") and v != "":
                x = float(v)
                check(math.isfinite(x), f"{k}={v}")
    rejected = {(x["topic"], x["stamp_ns"]) for x in exp["rejected_rows"]}
    values = [k for k in header if k not in ("time_s", "stamp_ns", "topic", "type")]
    for r in body:
        if (r["topic"], r["stamp_ns"]) in rejected:
            # A message that failed its check: its stamp, no values.
            check(all(r[k] == "" for k in values), f"a rejected message has values: {r}")
        elif r["topic"] != "attitude/estimate":
            check(r["lat_deg"] != "" or r["topic"] == "lbl/nav", f"no latitude: {r}")
    truth = [r for r in body if r["topic"] == exp["known_point"]["topic"]]
    kp = exp["known_point"]
    check(near(truth[0]["lat_deg"], kp["lat_deg"], 1e-9) and near(truth[0]["lon_deg"], kp["lon_deg"], 1e-9),
          f"first truth row {truth[0]}")
    stamps = [int(r["stamp_ns"]) for r in truth]
    check(stamps == sorted(stamps), "truth rows out of order")
    check(all(near(float(r["time_s"]), int(r["stamp_ns"]) * 1e-9, 1e-9) for r in truth), "time_s")
    # ains/nav is the truth moved by a known north/east offset.
    nav = {r["stamp_ns"]: r for r in body if r["topic"] == "ains/nav"}
    dn, de = exp["nav_offset_m"]
    for r in truth[::500]:
        n = nav[r["stamp_ns"]]
        check(abs(float(n["north_m"]) - float(r["north_m"]) - dn) < 1e-3, f"north {n} {r}")
        check(abs(float(n["east_m"]) - float(r["east_m"]) - de) < 1e-3, f"east {n} {r}")
    empty_depth = [r for r in nav.values() if r["depth_m"] == ""]
    check(len(empty_depth) == len(rejected), f"{len(empty_depth)} nav rows without depth")
    return f"{len(body)} rows"


# ---------------------------------------------------------------------- Foxglove


def foxglove_fields(schema, where):
    """Walks a channel's JSON Schema the way Foxglove turns one into message
    datatypes (its mcap-support JSON Schema reader): the root and every
    nested object need `"type": "object"` and `properties`; a property is
    either a `oneOf` of numeric `const`s (an enum) or has one `type` among
    boolean, string, number, integer, object, or array whose `items` have one
    of those types (no arrays of arrays). Returns the number of fields."""
    check(schema.get("type") == "object", f"{where}: type {schema.get('type')!r}, Foxglove needs object")
    check(isinstance(schema.get("properties"), dict), f"{where}: no properties")
    n = 0
    for name, field in schema["properties"].items():
        at = f"{where}.{name}"
        n += 1
        if "oneOf" in field:
            check(all(isinstance(a.get("const"), (int, float)) for a in field["oneOf"]), f"{at}: oneOf")
            continue
        t = field.get("type")
        check(isinstance(t, str), f"{at}: type {t!r} is not one name")
        if t == "object":
            n += foxglove_fields(field, at)
        elif t == "array":
            it = field.get("items", {}).get("type")
            check(it in ("boolean", "string", "number", "integer", "object"), f"{at}: items {it!r}")
            if it == "object":
                n += foxglove_fields(field["items"], at)
        else:
            check(t in ("boolean", "string", "number", "integer"), f"{at}: type {t!r}")
            check(field.get("contentEncoding") in (None, "base64"), f"{at}: contentEncoding")
    return n


LOCATION_FIX_REQUIRED = {
    "timestamp", "frame_id", "latitude", "longitude", "altitude",
    "position_covariance", "position_covariance_type",
}


def check_foxglove(path, exp):
    import jsonschema
    from mcap.reader import make_reader

    source = defaultdict(list)
    with open(exp["source"], "rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            source[channel.topic].append((message.log_time, message.publish_time))
    src_counts = {t: len(v) for t, v in source.items()}
    check(src_counts == exp["source_counts"], f"source {src_counts} != {exp['source_counts']}")

    validators = {}
    got = defaultdict(list)
    first = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        check(summary is not None, "no summary")
        for ch in summary.channels.values():
            schema = summary.schemas[ch.schema_id]
            check(ch.message_encoding == "json", f"{ch.topic}: {ch.message_encoding}")
            check(schema.encoding == "jsonschema", f"{ch.topic}: schema {schema.encoding}")
            js = json.loads(schema.data)
            check(js.get("type") == "object" and "properties" in js, f"{ch.topic}: schema {js}")
            jsonschema.Draft202012Validator.check_schema(js)
            foxglove_fields(js, ch.topic)
            if schema.name == "foxglove.LocationFix":
                check(ch.topic.startswith("/map/"), ch.topic)
                check(LOCATION_FIX_REQUIRED <= set(js["properties"]), f"{ch.topic}: {sorted(js['properties'])}")
                check(LOCATION_FIX_REQUIRED <= set(js.get("required", [])), f"{ch.topic}: required")
                ts = js["properties"]["timestamp"]["properties"]
                check(set(ts) == {"sec", "nsec"}, f"{ch.topic}: timestamp {ts}")
            validators[ch.id] = jsonschema.Draft202012Validator(js)
        topics = {ch.topic for ch in summary.channels.values()}
        check(set(exp["source_counts"]) <= topics, f"channels {sorted(topics)}")
        f.seek(0)
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            doc = json.loads(message.data)
            errors = list(validators[channel.id].iter_errors(doc))
            check(not errors, f"{channel.topic}: {errors[0].message if errors else ''}\n{doc}")
            got[channel.topic].append((message.log_time, message.publish_time))
            first.setdefault(channel.topic, (schema.name, doc))
    for topic, times in source.items():
        skipped = exp["skipped"].get(topic, 0)
        check(len(got[topic]) == len(times) - skipped, f"{topic}: {len(got[topic])} of {len(times)}")
        if not skipped:
            check(got[topic] == times, f"{topic}: log/publish times differ from the source")
    for t in exp["tracks"]:
        m = f"/map/{t}"
        check(len(got[m]) >= 2, f"{m}: {len(got[m])} location fixes")
        name, doc = first[m]
        check(name == "foxglove.LocationFix", f"{m}: schema {name}")
        check(doc["frame_id"] == t and len(doc["position_covariance"]) == 9, doc)
    kp = exp["known_point"]
    name, truth = first[kp["topic"]]
    check(name == "nauta.TruthState.v1", name)
    check(near(math.degrees(truth["lat_rad"]), kp["lat_deg"], 1e-12), truth)
    _, fix = first["/map/" + kp["topic"]]
    check(near(fix["latitude"], kp["lat_deg"]) and near(fix["longitude"], kp["lon_deg"]), fix)
    _, ev = first["run/events"]
    check(ev["process"] == "attitude" and ev["header"]["seq"] == 0, ev)
    _, lbl = first["lbl/nav"]
    check(len(lbl["p"]) == 16 and lbl["p"][1] == 1.0, lbl)
    with open(path, "rb") as f:
        nav = [json.loads(m.data) for _s, _c, m in make_reader(f).iter_messages(topics=["ains/nav"])]
    check(sum("depth_m" not in d for d in nav) == 1, "the non-finite depth is left out once")
    return f"{sum(len(v) for v in got.values())} messages on {len(got)} channels"


def main():
    fmt, out, expect = sys.argv[1:4]
    exp = json.loads(pathlib.Path(expect).read_text())
    checks = {
        "kml": check_kml,
        "geojson": check_geojson,
        "gpx": check_gpx,
        "csv": check_csv,
        "foxglove": check_foxglove,
    }
    print(f"ok {fmt}: {checks[fmt](out, exp)}")


if __name__ == "__main__":
    main()
