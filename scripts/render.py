#!/usr/bin/python3
"""Render an OBJ written by `crumple run` as a shaded PNG (matplotlib mplot3d).

    /usr/bin/python3 scripts/render.py final.obj out.png [--elev 35 --azim -60]
        [--size 6] [--dpi 150] [--title T] [--aux] [--crease-deg 30] [--no-creases]

What it draws
- Every triangle of the `f` lines, flat shaded with a directional light fixed relative to
  the camera (up-left-front of the viewer): two-sided Lambert, i = ambient + diffuse*|n.l|
  with n turned towards the camera. Paper has two sides: the side whose normal faces the
  camera takes the front colour (warm white), the other side a slightly cooler grey-blue.
- Crease lines: mesh edges whose dihedral angle (angle between the two adjacent face
  normals) exceeds --crease-deg are drawn darker (--no-creases to switch off).
- With --aux, the auxiliary springs (`l a b` lines: broken edges that hold a crease) in red.

How: one Poly3DCollection holds the triangles *and* the crease/aux segments (as
2-point polygons with their own edge colour), sorted every draw by mean depth
(zsort='average', painter's order). The projection is orthographic, so a segment is moved
a little towards the camera (which changes its depth but not its place on screen) to be
drawn after the triangles it lies on while still hidden by nearer sheet parts. Axes are
equally scaled (set_box_aspect on the data extents).

Python API: load_obj(path) -> (V, F, L); render(obj_path, png_path, **options);
render_mesh(V, F, L, ax=..., ...) draws into an existing 3D axes (used by figures.py).
"""
import argparse
import sys
import time

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

FRONT = np.array([0.97, 0.95, 0.89])   # warm white paper
BACK = np.array([0.86, 0.89, 0.93])    # the other side, cooler
CREASE = np.array([0.30, 0.27, 0.24])
AUX = np.array([0.85, 0.15, 0.10])


def load_obj(path):
    """Read `v`, `f` and `l` lines of an OBJ.

    Returns V (n,3 float64), F (m,3 int, 0-based; polygons fan-split), L (k,2 int, 0-based;
    polylines split into segments). Accepts `f a/b/c` forms and negative (relative) indices.
    """
    verts, faces, lines = [], [], []

    def idx(tok, n):
        i = int(tok.split("/")[0])
        return i - 1 if i > 0 else n + i

    with open(path) as fh:
        for line in fh:
            if not line or line[0] == "#":
                continue
            parts = line.split()
            if not parts:
                continue
            tag = parts[0]
            if tag == "v":
                verts.append((float(parts[1]), float(parts[2]), float(parts[3])))
            elif tag == "f":
                n = len(verts)
                ids = [idx(t, n) for t in parts[1:]]
                for k in range(1, len(ids) - 1):
                    faces.append((ids[0], ids[k], ids[k + 1]))
            elif tag == "l":
                n = len(verts)
                ids = [idx(t, n) for t in parts[1:]]
                for k in range(len(ids) - 1):
                    lines.append((ids[k], ids[k + 1]))
    V = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    L = np.asarray(lines, dtype=np.int64).reshape(-1, 2)
    return V, F, L


def face_normals(V, F):
    """Unit face normals and face areas."""
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    a = np.linalg.norm(c, axis=1)
    n = c / np.maximum(a, 1e-300)[:, None]
    return n, 0.5 * a


def interior_edges(F):
    """Edges shared by two faces: returns E (k,2 vertex ids), fa, fb (face ids), and `flip`
    (True where the two faces traverse the edge in the same direction, i.e. are
    inconsistently oriented, so one normal must be negated to compare them)."""
    m = len(F)
    a = F.reshape(-1)
    b = F[:, [1, 2, 0]].reshape(-1)
    fid = np.repeat(np.arange(m), 3)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    fwd = a < b
    order = np.lexsort((hi, lo))
    lo, hi, fid, fwd = lo[order], hi[order], fid[order], fwd[order]
    same = (lo[1:] == lo[:-1]) & (hi[1:] == hi[:-1])
    k = np.nonzero(same)[0]
    # a non-manifold edge (3+ faces) contributes its consecutive pairs; fine for a measure
    E = np.stack([lo[k], hi[k]], axis=1)
    return E, fid[k], fid[k + 1], fwd[k] == fwd[k + 1]


def dihedral_angles(V, F, normals=None):
    """Interior edges E and their dihedral angle in degrees (0 = flat)."""
    if normals is None:
        normals, _ = face_normals(V, F)
    E, fa, fb, flip = interior_edges(F)
    d = np.einsum("ij,ij->i", normals[fa], normals[fb])
    d = np.where(flip, -d, d)
    ang = np.degrees(np.arccos(np.clip(d, -1.0, 1.0)))
    return E, ang


def camera_frame(elev, azim):
    """Unit vectors (eye, up, right) in data space for mplot3d's elev/azim."""
    e, a = np.radians(elev), np.radians(azim)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    up = np.array([0.0, 0.0, 1.0]) - np.sin(e) * eye
    nu = np.linalg.norm(up)
    up = up / nu if nu > 1e-9 else np.array([-np.sin(a), np.cos(a), 0.0])
    right = np.cross(up, eye)
    return eye, up, right


def shade(normals, eye, light, ambient=0.45, diffuse=0.6, front=FRONT, back=BACK):
    """Two-sided flat Lambert shading -> (m,4) RGBA."""
    s = normals @ eye
    facing = s >= 0
    n = np.where(facing[:, None], normals, -normals)
    lam = np.clip(n @ light, 0.0, 1.0)
    base = np.where(facing[:, None], front[None, :], back[None, :])
    rgb = np.clip(base * (ambient + diffuse * lam)[:, None], 0, 1)
    return np.concatenate([rgb, np.ones((len(rgb), 1))], axis=1)


def _line_segments(V, F, L, normals, creases, aux, crease_deg):
    """The lines drawn over the faces, with their RGBA colours: creases (darker for sharper
    ones) and, when asked, the auxiliary springs L. Two lists, one entry per kind present."""
    segs_all, seg_col = [], []
    if creases and len(F):
        E, ang = dihedral_angles(V, F, normals)
        sel = ang > crease_deg
        if np.any(sel):
            t = np.clip((ang[sel] - crease_deg) / 60.0, 0.0, 1.0)
            alpha = 0.45 + 0.5 * t
            c = np.concatenate([np.tile(CREASE, (sel.sum(), 1)), alpha[:, None]], axis=1)
            segs_all.append(V[E[sel]])
            seg_col.append(c)
    if aux and L is not None and len(L):
        segs_all.append(V[np.asarray(L)])
        seg_col.append(np.concatenate([np.tile(AUX, (len(L), 1)),
                                       np.full((len(L), 1), 0.8)], axis=1))
    return segs_all, seg_col


def _fit_view(ax, V, elev, azim, up, right, center, radius, fill):
    """Equal scaling, object filling the view: limits are a cube around `center` (default:
    the middle of the object's on-screen extent); `radius` is the on-screen half-size in
    data units to fit (default: the object's). mplot3d draws a screen-plane disk of
    radius 1 with limits +-1 at 0.57 of the axes' width in ortho mode (measured, any view)."""
    if len(V):
        c0 = 0.5 * (V.min(axis=0) + V.max(axis=0)) if center is None else np.asarray(center, float)
        P = V - c0
        sx, sy = P @ right, P @ up
        if center is None:
            mx, my = 0.5 * (sx.max() + sx.min()), 0.5 * (sy.max() + sy.min())
            c0 = c0 + mx * right + my * up
            sx, sy = sx - mx, sy - my
        if radius is None:
            radius = max(float(np.abs(sx).max()), float(np.abs(sy).max()), 1e-12)
    else:
        c0, radius = np.zeros(3), 1.0
    half = radius * 0.57 / fill
    ax.set_xlim(c0[0] - half, c0[0] + half)
    ax.set_ylim(c0[1] - half, c0[1] + half)
    ax.set_zlim(c0[2] - half, c0[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()


def render_mesh(V, F, L=None, ax=None, elev=35.0, azim=-60.0, crease_deg=30.0,
                creases=True, aux=False, crease_width=0.5, seam_width=0.25, light=None,
                center=None, radius=None, fill=0.92, bias=0.35):
    """Draw the mesh into a 3D axes `ax` (made if None). Returns ax.

    center, radius: fix the view (data units; e.g. the same for every panel of a row);
    by default the object fills `fill` of the axes.
    """
    if ax is None:
        fig = plt.figure(figsize=(6, 6))
        ax = fig.add_subplot(projection="3d", proj_type="ortho")
    V = np.asarray(V, dtype=float)
    F = np.asarray(F, dtype=np.int64)
    eye, up, right = camera_frame(elev, azim)
    if light is None:
        light = 0.75 * eye + 0.55 * up - 0.35 * right
    light = np.asarray(light, float) / np.linalg.norm(light)
    normals, _ = face_normals(V, F)
    colors = shade(normals, eye, light)
    verts = list(V[F])    # (m,3,3)
    fcol = [colors]
    ecol = [colors]       # seams painted in the face colour hide antialiasing cracks
    segs_all, seg_col = _line_segments(V, F, L, normals, creases, aux, crease_deg)
    if segs_all:
        segs = np.concatenate(segs_all)
        # depth bias towards the camera, per segment: a fraction of its own length (enough
        # to come after the two triangles it bounds, small enough to stay behind sheet
        # layers lying in front of it)
        seglen = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
        segs = segs + (bias * seglen)[:, None, None] * eye[None, None, :]
        verts += list(segs)
        fcol.append(np.zeros((len(segs), 4)))
        ecol.append(np.concatenate(seg_col))
    lw = seam_width if not segs_all else crease_width
    # one linewidth per collection (mplot3d does not reorder per-item widths): seams are
    # drawn at the same width but in the face colour, so they are invisible
    coll = Poly3DCollection(verts, facecolors=np.concatenate(fcol), edgecolors=np.concatenate(ecol),
                            linewidths=lw, zsort="average", antialiased=True)
    ax.add_collection3d(coll)
    _fit_view(ax, V, elev, azim, up, right, center, radius, fill)
    return ax


def render(obj_path, png_path, elev=35.0, azim=-60.0, size=6.0, dpi=150, title=None,
           aux=False, crease_deg=30.0, creases=True, background="white", fill=0.92,
           center=None, radius=None, crease_width=0.5):
    """Render `obj_path` to `png_path`. Returns the number of triangles drawn."""
    V, F, L = load_obj(obj_path)
    fig = plt.figure(figsize=(size, size), facecolor=background)
    ax = fig.add_axes([0, 0, 1, 0.94 if title else 1.0], projection="3d", proj_type="ortho")
    ax.set_facecolor(background)
    render_mesh(V, F, L, ax=ax, elev=elev, azim=azim, crease_deg=crease_deg,
                creases=creases, aux=aux, fill=fill, center=center, radius=radius,
                crease_width=crease_width)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.savefig(png_path, dpi=dpi, facecolor=background)
    plt.close(fig)
    return len(F)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("obj")
    p.add_argument("png")
    p.add_argument("--elev", type=float, default=35.0)
    p.add_argument("--azim", type=float, default=-60.0)
    p.add_argument("--size", type=float, default=6.0, help="figure size in inches (square)")
    p.add_argument("--dpi", type=int, default=150)
    p.add_argument("--title")
    p.add_argument("--aux", action="store_true", help="draw auxiliary springs (l lines)")
    p.add_argument("--crease-deg", type=float, default=30.0,
                   help="draw edges with a dihedral angle above this darker")
    p.add_argument("--no-creases", action="store_true")
    p.add_argument("--fill", type=float, default=0.92,
                   help="fraction of the image the object spans")
    p.add_argument("--crease-width", type=float, default=0.5, help="crease line width (pt)")
    a = p.parse_args(argv)
    t0 = time.time()
    n = render(a.obj, a.png, elev=a.elev, azim=a.azim, size=a.size, dpi=a.dpi, title=a.title,
               aux=a.aux, crease_deg=a.crease_deg, creases=not a.no_creases, fill=a.fill,
               crease_width=a.crease_width)
    print(f"render: {n} triangles -> {a.png} in {time.time() - t0:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
