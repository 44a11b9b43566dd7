#!/usr/bin/python3
"""Crease and compaction measures of a crumpled sheet (an OBJ written by `crumple run`).

    /usr/bin/python3 scripts/crease.py final.obj [--ref initial.obj | --ref-area A]
        [--deg 30]            -> prints one JSON object

Measures
- crease_length: total current length of the mesh edges (edges shared by two triangles of
  the `f` lines; auxiliary `l` springs are not mesh edges) whose dihedral angle, the angle
  between the two adjacent face normals, exceeds `deg` (30 degrees by default). In the
  sheet's units.
- crease_norm = crease_length / sqrt(A0), A0 the area of the *initial* sheet.
  Why sqrt(area) and not the initial total edge length: crease length is a length on the
  sheet, so dividing by the sheet's side-length scale sqrt(A0) gives a pure number that does
  not depend on the unit (a 350-unit gingerbread man and the unit square compare directly)
  nor on the mesh resolution. The initial total edge length grows with the resolution
  (about 3N for an N x N unit grid), so the same crease pattern on a 32x32 and a 64x64 grid
  would get different scores; and the adaptive mesh refines, so "fraction of edges" is not
  a fixed quantity either. crease_norm = 1 means one sheet-width of crease line.
  A0 comes from --ref (an OBJ of the undeformed sheet, e.g. the input mesh) or --ref-area;
  without either, the current triangle area is used (near-inextensible paper keeps its
  area to within the spring strain; the output says which was used).
- crease_edges: how many edges passed the threshold; max_dihedral_deg; mean_dihedral_deg.
- rms_radius: compaction radius, the RMS distance of the vertices from their centroid
  (vertex-count weighted, as asked; refined regions have more vertices, so
  rms_radius_area, the same with triangle-centroid positions weighted by triangle area, is
  also given). rms_radius_norm = rms_radius / sqrt(A0). For reference, a flat unit square
  has an RMS radius of sqrt(1/6) = 0.408 (continuum).

Python API: crease_stats(V, F, L=None, deg=30, ref_area=None) -> dict; measure(path, ...).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from render import load_obj, face_normals, dihedral_angles  # noqa: E402


def sheet_area(V, F):
    return float(face_normals(V, F)[1].sum())


def crease_stats(V, F, L=None, deg=30.0, ref_area=None):
    V = np.asarray(V, float)
    F = np.asarray(F, np.int64)
    normals, areas = face_normals(V, F)
    E, ang = dihedral_angles(V, F, normals)
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    sel = ang > deg
    area_now = float(areas.sum())
    area_src = "ref" if ref_area is not None else "current"
    A0 = float(ref_area) if ref_area is not None else area_now
    used = np.unique(F)
    P = V[used]
    c = P.mean(axis=0)
    rms = float(np.sqrt(((P - c) ** 2).sum(axis=1).mean()))
    tc = V[F].mean(axis=1)
    w = areas / max(areas.sum(), 1e-300)
    ca = (tc * w[:, None]).sum(axis=0)
    rms_a = float(np.sqrt((((tc - ca) ** 2).sum(axis=1) * w).sum()))
    s = np.sqrt(A0)
    return {
        "vertices": int(len(used)),
        "triangles": int(len(F)),
        "aux_springs": int(0 if L is None else len(L)),
        "deg": float(deg),
        "crease_length": float(lengths[sel].sum()),
        "crease_norm": float(lengths[sel].sum() / s),
        "crease_edges": int(sel.sum()),
        "interior_edges": int(len(E)),
        "max_dihedral_deg": float(ang.max()) if len(ang) else 0.0,
        "mean_dihedral_deg": float(ang.mean()) if len(ang) else 0.0,
        "rms_radius": rms,
        "rms_radius_area": rms_a,
        "rms_radius_norm": rms / s,
        "area": area_now,
        "ref_area": A0,
        "ref_area_source": area_src,
    }


def measure(path, deg=30.0, ref=None, ref_area=None):
    """Crease stats of the OBJ at `path`; `ref` an OBJ of the undeformed sheet (for A0)."""
    V, F, L = load_obj(path)
    if ref_area is None and ref is not None:
        Vr, Fr, _ = load_obj(ref)
        ref_area = sheet_area(Vr, Fr)
    d = crease_stats(V, F, L, deg=deg, ref_area=ref_area)
    d["file"] = str(path)
    return d


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("obj", nargs="+")
    p.add_argument("--deg", type=float, default=30.0, help="dihedral threshold in degrees")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--ref", help="OBJ of the initial sheet (its area normalises)")
    g.add_argument("--ref-area", type=float, help="initial sheet area")
    a = p.parse_args(argv)
    out = [measure(f, a.deg, a.ref, a.ref_area) for f in a.obj]
    print(json.dumps(out[0] if len(out) == 1 else out, indent=2))


if __name__ == "__main__":
    main()
