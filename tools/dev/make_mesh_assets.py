#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Generates assets/meshes/bowl.obj and the small test meshes in tests/data/mesh/.

Run from anywhere: python3 tools/dev/make_mesh_assets.py
Output is deterministic (no randomness, fixed formatting), so re-running gives the same bytes.
"""
import math
import os
import struct

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DATA = os.path.join(ROOT, "tests", "data", "mesh")
ASSETS = os.path.join(ROOT, "assets", "meshes")

# Unit cube [0,1]^3: corners indexed by bits (x = bit 0, y = bit 1, z = bit 2).
CUBE_V = [((i & 1) * 1.0, ((i >> 1) & 1) * 1.0, ((i >> 2) & 1) * 1.0) for i in range(8)]
# Quads counter-clockwise seen from outside.
CUBE_QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
CUBE_TRIS = [t for q in CUBE_QUADS for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
# Kuhn split of the cube into 6 positively oriented tets around the diagonal 0-7.
KUHN = [(0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)]
GMSH_EDGES = [(0, 1), (1, 2), (2, 0), (3, 0), (3, 2), (3, 1)]
# TetGen 1.5 -o2 order of the mid-edge nodes (see src/mesh/tetgen_reader.cpp).
TETGEN_EDGES = [(2, 3), (0, 3), (0, 1), (1, 2), (1, 3), (0, 2)]


def det_orient(p):
    a = [p[1][k] - p[0][k] for k in range(3)]
    b = [p[2][k] - p[0][k] for k in range(3)]
    c = [p[3][k] - p[0][k] for k in range(3)]
    return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))


for t in KUHN:
    assert det_orient([CUBE_V[i] for i in t]) > 0, t


def write(path, text, mode="w"):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, mode) as f:
        f.write(text)


def fmt(x):
    return repr(float(x))


def tet10_mesh():
    """Cube nodes + one node per edge midpoint; tets in Gmsh Tet10 order."""
    nodes = list(CUBE_V)
    mid = {}
    tets = []
    for t in KUHN:
        row = list(t)
        for a, b in GMSH_EDGES:
            key = (min(t[a], t[b]), max(t[a], t[b]))
            if key not in mid:
                pa, pb = CUBE_V[key[0]], CUBE_V[key[1]]
                nodes.append(tuple(0.5 * (pa[k] + pb[k]) for k in range(3)))
                mid[key] = len(nodes) - 1
            row.append(mid[key])
        tets.append(row)
    return nodes, tets


# ---- surface files ------------------------------------------------------------------------

def cube_obj():
    lines = ["# unit cube: quads, v/vt/vn forms, a negative index, records we ignore", "mtllib none.mtl", "o cube"]
    lines += ["v %s %s %s" % tuple(fmt(c) for c in v) for v in CUBE_V]
    lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vn 0 0 1", "g faces", "s off", "usemtl none"]
    for n, q in enumerate(CUBE_QUADS):
        if n == 0:
            lines.append("f " + " ".join("%d/%d" % (i + 1, 1) for i in q))
        elif n == 1:
            lines.append("f " + " ".join("%d/%d/1" % (i + 1, 2) for i in q))
        elif n == 2:
            lines.append("f " + " ".join("%d//1" % (i + 1) for i in q))
        elif n == 3:
            lines.append("f " + " ".join("%d" % (i - 8) for i in q))  # negative: -8 is vertex 1
        else:
            lines.append("f " + " ".join("%d" % (i + 1) for i in q))
    return "\n".join(lines) + "\n"


def normal(tri):
    p = [CUBE_V[i] for i in tri]
    a = [p[1][k] - p[0][k] for k in range(3)]
    b = [p[2][k] - p[0][k] for k in range(3)]
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def cube_stl_ascii():
    out = ["solid cube"]
    for t in CUBE_TRIS:
        out.append("  facet normal %s %s %s" % tuple(fmt(c) for c in normal(t)))
        out.append("    outer loop")
        for i in t:
            out.append("      vertex %s %s %s" % tuple(fmt(c) for c in CUBE_V[i]))
        out.append("    endloop")
        out.append("  endfacet")
    out.append("endsolid cube")
    return "\n".join(out) + "\n"


def cube_stl_binary(count=None, cut=None):
    # The header deliberately starts with "solid": many exporters do that, and the reader must
    # still detect binary by the 84 + 50 n size rule.
    header = b"solid cube (binary, header starts with solid on purpose)".ljust(80, b" ")
    body = b""
    for t in CUBE_TRIS:
        body += struct.pack("<3f", *normal(t))
        for i in t:
            body += struct.pack("<3f", *CUBE_V[i])
        body += struct.pack("<H", 0)
    data = header + struct.pack("<I", len(CUBE_TRIS) if count is None else count) + body
    return data if cut is None else data[:cut]


def ply_header(fmt_name, nv, nf, extra_element=True):
    h = ["ply", "format %s 1.0" % fmt_name, "comment unit cube with extra properties to skip",
         "element vertex %d" % nv, "property float x", "property float y", "property double z",
         "property uchar red", "property list uchar int extra_list", "property float nx"]
    h += ["element face %d" % nf, "property list uchar int vertex_indices", "property int flags"]
    if extra_element:
        h += ["element edge 1", "property int vertex1", "property int vertex2"]
    h.append("end_header")
    return "\n".join(h) + "\n"


def cube_ply_ascii():
    out = ply_header("ascii", 8, 6)
    for v in CUBE_V:
        out += "%s %s %s 255 2 7 8 0.5\n" % tuple(fmt(c) for c in v)
    for q in CUBE_QUADS:
        out += "4 %d %d %d %d 0\n" % q
    out += "0 1\n"
    return out


def cube_ply_binary(endian):
    e = "<" if endian == "le" else ">"
    out = ply_header("binary_little_endian" if endian == "le" else "binary_big_endian", 8, 6).encode()
    for v in CUBE_V:
        out += struct.pack(e + "ffdBBiif", v[0], v[1], v[2], 255, 2, 7, 8, 0.5)
    for q in CUBE_QUADS:
        out += struct.pack(e + "B4ii", 4, *q, 0)
    out += struct.pack(e + "ii", 0, 1)
    return out


# ---- tet files ----------------------------------------------------------------------------

def msh22(nodes, tets, tag_of=lambda i: 10 + 3 * i, inverted=(), extra_triangles=True):
    etype = 4 if len(tets[0]) == 4 else 11
    out = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "1", "3 1 \"solid\"", "$EndPhysicalNames"]
    out += ["$Nodes", str(len(nodes))]
    out += ["%d %s %s %s" % ((tag_of(i),) + tuple(fmt(c) for c in p)) for i, p in enumerate(nodes)]
    out += ["$EndNodes", "$Elements"]
    elems = []
    if extra_triangles:
        elems.append("2 2 2 1 1 %d %d %d" % (tag_of(0), tag_of(2), tag_of(3)))
        elems.append("3 15 2 1 1 %d" % tag_of(0))
    for n, t in enumerate(tets):
        t = list(t)
        if n in inverted:
            t[1], t[2] = t[2], t[1]
            if len(t) == 10:
                t[4], t[6] = t[6], t[4]
                t[8], t[9] = t[9], t[8]
        elems.append("%d %d 2 1 1 %s" % (100 + n, etype, " ".join(str(tag_of(i)) for i in t)))
    out += [str(len(elems))] + elems + ["$EndElements"]
    return "\n".join(out) + "\n"


def msh41(nodes, tets, tag_of=lambda i: 10 + 3 * i):
    etype = 4 if len(tets[0]) == 4 else 11
    tags = [tag_of(i) for i in range(len(nodes))]
    out = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat",
           "$Entities", "0 0 0 1", "1 0 0 0 1 1 1 0 0", "$EndEntities"]
    # Two node blocks (a point entity with one node, the volume with the rest), as Gmsh writes.
    out += ["$Nodes", "2 %d %d %d" % (len(nodes), min(tags), max(tags))]
    out += ["0 1 0 1", str(tags[0]), "%s %s %s" % tuple(fmt(c) for c in nodes[0])]
    out += ["3 1 0 %d" % (len(nodes) - 1)]
    out += [str(t) for t in tags[1:]]
    out += ["%s %s %s" % tuple(fmt(c) for c in p) for p in nodes[1:]]
    out += ["$EndNodes", "$Elements", "2 %d 1 %d" % (len(tets) + 1, len(tets) + 1)]
    out += ["2 1 2 1", "1 %d %d %d" % (tags[0], tags[2], tags[3])]
    out += ["3 1 %d %d" % (etype, len(tets))]
    out += ["%d %s" % (n + 2, " ".join(str(tags[i]) for i in t)) for n, t in enumerate(tets)]
    out += ["$EndElements"]
    return "\n".join(out) + "\n"


def tetgen_files(nodes, tets, first=1):
    node = ["# unit cube", "%d 3 0 0" % len(nodes)]
    node += ["%d %s %s %s" % ((i + first,) + tuple(fmt(c) for c in p)) for i, p in enumerate(nodes)]
    if len(tets[0]) == 10:
        # Write in TetGen's own -o2 order.
        rows = []
        for t in tets:
            pos = {}
            for k, (a, b) in enumerate(GMSH_EDGES):
                pos[(min(a, b), max(a, b))] = t[4 + k]
            rows.append(list(t[:4]) + [pos[(min(a, b), max(a, b))] for a, b in TETGEN_EDGES])
    else:
        rows = tets
    ele = ["%d %d 0" % (len(rows), len(rows[0]))]
    ele += ["%d %s" % (n + first, " ".join(str(i + first) for i in t)) for n, t in enumerate(rows)]
    return "\n".join(node) + "\n", "\n".join(ele) + "\n# generated by tools/dev/make_mesh_assets.py\n"


# ---- bowl ---------------------------------------------------------------------------------

def revolve_obj(prof, segments, comment):
    """Revolves a closed profile [(r, z), ...] about the z axis into a closed OBJ surface. The
    profile starts and ends on the axis (r = 0), which become poles."""
    verts = []
    ids = []
    for (r, z) in prof:
        if r == 0.0:
            verts.append((0.0, 0.0, z))
            ids.append([len(verts) - 1] * segments)
        else:
            row = []
            for j in range(segments):
                a = 2 * math.pi * j / segments
                verts.append((r * math.cos(a), r * math.sin(a), z))
                row.append(len(verts) - 1)
            ids.append(row)
    tris = []
    for k in range(len(prof) - 1):
        for j in range(segments):
            j1 = (j + 1) % segments
            a, b, c, d = ids[k][j], ids[k][j1], ids[k + 1][j1], ids[k + 1][j]
            for t in ((a, b, c), (a, c, d)):
                if len(set(t)) == 3:
                    tris.append(t)
    vol = 0.0
    for t in tris:
        p = [verts[i] for i in t]
        vol += det_orient([(0, 0, 0)] + p) / 6.0
    if vol < 0:
        tris = [(t[0], t[2], t[1]) for t in tris]
    lines = ["# " + comment + "; metres",
             "# generated by tools/dev/make_mesh_assets.py (revolved profile, %d segments)" % segments]
    lines += ["v %.6f %.6f %.6f" % v for v in verts]
    lines += ["f %d %d %d" % (t[0] + 1, t[1] + 1, t[2] + 1) for t in tris]
    return "\n".join(lines) + "\n", len(tris)


def bowl_obj(segments=48):
    """A thick-walled bowl, 12 cm across, 5 cm tall, 4 mm walls."""
    outer_r, height, wall = 0.06, 0.05, 0.004
    prof = []
    n_outer = 9
    for i in range(n_outer + 1):  # outer wall: z = h (r/R)^2 from the bottom centre to the rim
        r = outer_r * i / n_outer
        prof.append((r, height * (r / outer_r) ** 2))
    inner_r = outer_r - wall
    prof.append((outer_r - wall / 2, height + wall / 4))  # rounded rim
    n_inner = 8
    for i in range(n_inner, -1, -1):  # inner wall back to the axis, offset up by the wall
        r = inner_r * i / n_inner
        prof.append((r, wall + (height - wall) * (r / inner_r) ** 2))
    return revolve_obj(prof, segments, "thick-walled bowl, 12 cm diameter, 4 mm walls")


def glass_obj(segments=40):
    """A drinking glass (tumbler): 6.4 cm across, 9 cm tall, 2.5 mm walls, 6 mm base."""
    outer_r, height, wall, base = 0.032, 0.09, 0.0025, 0.006
    prof = [(0.0, 0.0), (outer_r * 0.5, 0.0), (outer_r - 0.002, 0.0), (outer_r, 0.002)]
    for i in range(1, 11):  # outer wall, slightly flared
        z = 0.002 + (height - 0.002) * i / 10
        prof.append((outer_r + 0.003 * i / 10, z))
    rim_r = outer_r + 0.003
    prof.append((rim_r - wall / 2, height + wall / 3))  # rounded rim
    for i in range(10, -1, -1):  # inner wall down to the base
        z = base + (height - base) * i / 10
        prof.append((outer_r - wall + 0.003 * i / 10, z))
    prof += [((outer_r - wall) * 0.5, base), (0.0, base)]
    return revolve_obj(prof, segments, "drinking glass, 6.4 cm diameter, 9 cm tall, 2.5 mm walls")


def mug_obj(segments=48, outer_r=0.04, height=0.11, wall=0.004, base=0.006, name="mug", n_wall=11):
    """A mug without handle (an open cylinder shell on a flat bottom): 8 cm across, 11 cm tall,
    4 mm wall, 6 mm base -- a thin-walled shape, where linear tets lock (wall / size = 0.036)."""
    prof = [(0.0, 0.0), (outer_r * 0.5, 0.0), (outer_r, 0.0)]
    for i in range(1, n_wall + 1):  # outer wall, straight
        prof.append((outer_r, height * i / n_wall))
    prof.append((outer_r - wall, height))  # flat rim
    for i in range(n_wall - 1, -1, -1):  # inner wall down to the base
        prof.append((outer_r - wall, base + (height - base) * i / n_wall))
    prof += [((outer_r - wall) * 0.5, base), (0.0, base)]
    return revolve_obj(prof, segments, "%s: %.0f cm across, %.0f cm tall, %.1f mm wall, %.0f mm base" %
                       (name, 200 * outer_r, 100 * height, 1000 * wall, 1000 * base))


def main():
    mug, ntris = mug_obj()
    write(os.path.join(ASSETS, "mug.obj"), mug)
    print("mug.obj: %d triangles" % ntris)
    # Small thin-walled cup for fast tests (3.5k tets): 4 cm across and tall, 3 mm wall (2 V / A =
    # 3 mm, 7.5% of the extent), coarsely faceted.
    cup, ntris = mug_obj(segments=12, outer_r=0.02, height=0.04, wall=0.003, base=0.004, name="small cup", n_wall=2)
    write(os.path.join(DATA, "thin_cup.obj"), cup)
    print("thin_cup.obj: %d triangles" % ntris)
    bowl, ntris = bowl_obj()
    write(os.path.join(ASSETS, "bowl.obj"), bowl)
    print("bowl.obj: %d triangles" % ntris)
    glass, ntris = glass_obj()
    write(os.path.join(ASSETS, "glass.obj"), glass)
    print("glass.obj: %d triangles" % ntris)

    write(os.path.join(DATA, "cube.obj"), cube_obj())
    write(os.path.join(DATA, "cube_ascii.stl"), cube_stl_ascii())
    write(os.path.join(DATA, "cube_binary.stl"), cube_stl_binary(), "wb")
    write(os.path.join(DATA, "cube_ascii.ply"), cube_ply_ascii())
    write(os.path.join(DATA, "cube_binary_le.ply"), cube_ply_binary("le"), "wb")
    write(os.path.join(DATA, "cube_binary_be.ply"), cube_ply_binary("be"), "wb")

    tet4 = [list(t) for t in KUHN]
    n10, t10 = tet10_mesh()
    write(os.path.join(DATA, "cube_tet4_v22.msh"), msh22(CUBE_V, tet4))
    write(os.path.join(DATA, "cube_tet10_v22.msh"), msh22(n10, t10))
    write(os.path.join(DATA, "cube_tet4_v41.msh"), msh41(CUBE_V, tet4))
    write(os.path.join(DATA, "cube_tet10_v41.msh"), msh41(n10, t10))
    node, ele = tetgen_files(CUBE_V, tet4, first=1)
    write(os.path.join(DATA, "cube_tet4.node"), node)
    write(os.path.join(DATA, "cube_tet4.ele"), ele)
    node, ele = tetgen_files(n10, t10, first=0)
    write(os.path.join(DATA, "cube_tet10.node"), node)
    write(os.path.join(DATA, "cube_tet10.ele"), ele)

    # ---- malformed and repairable files ----
    bad = os.path.join(DATA, "bad")
    obj = cube_obj()
    write(os.path.join(bad, "bad_index.obj"), obj.replace("f 1 5 7 3", "f 1 5 9 3"))
    write(os.path.join(bad, "nan.obj"), obj.replace("v 1.0 1.0 1.0", "v 1.0 nan 1.0"))
    write(os.path.join(bad, "open.obj"), obj.replace("f 2 4 8 6\n", ""))
    write(os.path.join(bad, "flipped.obj"), obj.replace("f 2 4 8 6", "f 6 8 4 2"))
    write(os.path.join(bad, "truncated.stl"), cube_stl_binary(cut=84 + 50 * 5 + 17), "wb")
    write(os.path.join(bad, "huge_count.stl"), cube_stl_binary(count=10 ** 9), "wb")
    write(os.path.join(bad, "truncated_ascii.stl"), cube_stl_ascii()[:400])
    ply = cube_ply_binary("le")
    write(os.path.join(bad, "truncated.ply"), ply[:len(ply) - 40], "wb")
    write(os.path.join(bad, "huge_count.ply"), ply.replace(b"element vertex 8", b"element vertex 1000000000"), "wb")
    write(os.path.join(bad, "bad_index.ply"), cube_ply_ascii().replace("4 1 3 7 5 0", "4 1 3 70 5 0"))
    msh = msh22(CUBE_V, tet4)
    write(os.path.join(bad, "truncated.msh"), msh[:msh.index("$Elements") + 30])
    write(os.path.join(bad, "bad_index.msh"), msh.replace("105 4 2 1 1 10 25 13 31", "105 4 2 1 1 10 25 13 90211"))
    write(os.path.join(bad, "nan.msh"), msh.replace("13 1.0 0.0 0.0", "13 1.0 inf 0.0"))
    write(os.path.join(bad, "huge_count.msh"), msh.replace("$Nodes\n8\n", "$Nodes\n1000000000\n"))
    write(os.path.join(bad, "surface_only.msh"), msh22(CUBE_V, tet4).split("$Elements")[0] +
          "$Elements\n1\n2 2 2 1 1 10 16 19\n$EndElements\n")
    write(os.path.join(bad, "inverted.msh"), msh22(CUBE_V, tet4, inverted=(1, 4)))
    write(os.path.join(bad, "inverted_tet10.msh"), msh22(n10, t10, inverted=(2,)))
    # Degenerate: tet 0 made flat by moving node 7's use to node 2 -> (0,1,3,2) all in z = 0.
    write(os.path.join(bad, "degenerate.msh"), msh.replace("100 4 2 1 1 10 13 19 31", "100 4 2 1 1 10 13 19 16"))
    # Unreferenced: an extra node that no tet uses.
    write(os.path.join(bad, "unreferenced.msh"), msh.replace("$Nodes\n8\n", "$Nodes\n9\n500 5.0 5.0 5.0\n"))
    node, ele = tetgen_files(CUBE_V, tet4, first=1)
    write(os.path.join(bad, "huge_count.node"), node.replace("8 3 0 0", "1000000000 3 0 0"))
    write(os.path.join(bad, "huge_count.ele"), ele)
    write(os.path.join(bad, "bad_index.node"), node)
    write(os.path.join(bad, "bad_index.ele"), ele.replace("6 1 6 2 8", "6 1 6 2 80"))


if __name__ == "__main__":
    main()
