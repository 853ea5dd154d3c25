#!/usr/bin/python3
"""Checks a run's result.xmf the way ParaView's XDMF reader reads it, when no such reader is installed.

    check_xdmf.py RUN_DIR

Debian 12 has no XDMF reader this test can use without ParaView: python3-xdmf (Xdmf 3) fails to import
(undefined symbol XdmfUnstructuredGridCast in its _Xdmf module), and pvpython comes with the paraview
package (176 packages with Qt; test_paraview.sh uses it when it is on PATH). So this checks what the reader
relies on: the XML parses; every temporal collection's steps have increasing times; every HDF DataItem names
a dataset of result.h5 with the shape and number type the item declares; topologies and attributes agree with
the number of points and cells; and the debris hexahedra are the scene's boxes at the recorded pose (edge
lengths the box's size, centre the recorded position).
"""
import json
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

run = sys.argv[1]
xmf = os.path.join(run, "result.xmf")
h5 = h5py.File(os.path.join(run, "result.h5"), "r")
root = ET.parse(xmf).getroot()
assert root.tag == "Xdmf", root.tag
problems = []


def dims(item):
    return tuple(int(d) for d in item.get("Dimensions").split())


def values(item):
    """The item's array: from result.h5 for Format=HDF (checked against the declared shape and type)."""
    shape = dims(item)
    if item.get("Format") == "HDF":
        file, path = item.text.strip().split(":", 1)
        if file != "result.h5":
            problems.append(f"{path}: refers to {file}, not result.h5 beside the .xmf")
        if path not in h5:
            problems.append(f"{path}: no such dataset")
            return np.zeros(shape)
        d = h5[path]
        if tuple(d.shape) != shape:
            problems.append(f"{path}: shape {d.shape}, the XDMF says {shape}")
        want = "f" if item.get("NumberType", "Float") == "Float" else "i"
        if d.dtype.kind != want or (want == "f" and d.dtype.itemsize != int(item.get("Precision", "4"))):
            problems.append(f"{path}: type {d.dtype}, the XDMF says {item.get('NumberType')} {item.get('Precision')}")
        return d[()]
    a = np.array(item.text.split(), dtype=float)
    if a.size != int(np.prod(shape)):
        problems.append(f"inline item: {a.size} values for dimensions {shape}")
    return a.reshape(shape)


scene = json.loads(h5.attrs["scene_json"])
sizes = [np.array(b["size"], dtype=float) for b in scene.get("debris", {}).get("bodies", [])]
names = [b["name"] for b in scene.get("debris", {}).get("bodies", [])]
collections = {}
for coll in root.find("Domain").findall("Grid"):
    assert coll.get("GridType") == "Collection" and coll.get("CollectionType") == "Temporal", coll.attrib
    times = []
    for g in coll.findall("Grid"):
        t = float(g.find("Time").get("Value"))
        times.append(t)
        topo = g.find("Topology")
        xyz = values(g.find("Geometry").find("DataItem"))
        n_points = xyz.shape[0]
        n_cells = int(topo.get("NumberOfElements"))
        if topo.get("TopologyType") == "Polyvertex":
            if n_cells != n_points:
                problems.append(f"{g.get('Name')}: {n_cells} vertices for {n_points} points")
        elif topo.get("TopologyType") == "Hexahedron":
            conn = values(topo.find("DataItem")).astype(int)
            if conn.shape != (n_cells, 8) or conn.max() >= n_points or conn.min() < 0:
                problems.append(f"{g.get('Name')}: connectivity {conn.shape} out of range of {n_points} points")
            for b, cell in enumerate(conn):
                c = xyz[cell].astype(float)
                edges = np.array([np.linalg.norm(c[1] - c[0]), np.linalg.norm(c[3] - c[0]), np.linalg.norm(c[4] - c[0])])
                # float32 corners of boxes a metre from the origin: 1e-6 relative
                if not np.allclose(edges, sizes[b], rtol=0, atol=1e-5):
                    problems.append(f"{g.get('Name')} body {b}: edges {edges}, the scene's size {sizes[b]}")
                series = h5[f"/debris/{names[b]}/resampled"]
                k = int(np.argmin(np.abs(series["time"][()] - t)))
                if not np.allclose(c.mean(axis=0), series["position"][k], atol=1e-5):
                    problems.append(f"{g.get('Name')} body {b}: centre {c.mean(axis=0)}, recorded {series['position'][k]}")
        else:
            problems.append(f"{g.get('Name')}: unexpected topology {topo.get('TopologyType')}")
        for a in g.findall("Attribute"):
            v = values(a.find("DataItem"))
            want = n_points if a.get("Center") == "Node" else n_cells
            if v.shape[0] != want:
                problems.append(f"{g.get('Name')}/{a.get('Name')}: {v.shape[0]} rows for {want} {a.get('Center')}s")
    if any(b <= a for a, b in zip(times, times[1:])):
        problems.append(f"{coll.get('Name')}: times not increasing")
    collections[coll.get("Name")] = len(times)

print("collections:", collections)
if problems:
    print("\n".join(problems[:20]))
    sys.exit(1)
