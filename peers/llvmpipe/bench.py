#!/usr/bin/env python3
"""Peer benchmark: depth cube maps of the thesis scenes drawn by Mesa's llvmpipe.

For every point light of a scene, the scene's triangles are drawn into a cube map of
6 faces x N x N (90-degree perspective per face) with OpenGL on the CPU (Mesa llvmpipe,
EGL headless, through moderngl), in two variants:

  depth      a GL_DEPTH_COMPONENT cube map only (no colour attachment, empty fragment shader)
  depth+id   the same depth cube map plus an R32UI colour cube map that receives
             gl_PrimitiveID (the triangle's index in the scene's triangle list)

The geometry is uploaded once per scene (one vertex buffer of float32 positions, one
uint32 index buffer, one indexed draw call per face). The timed region of one repetition
is: for each of the 6 faces bind its framebuffer, clear it, set the face's matrix and draw
every triangle of the scene; then glFinish. Per light: 1 warm-up, then --reps timed
repetitions; the per-light figure is their median. The table gives, per scene,
resolution and variant, the median over the scene's lights of those per-light medians.

Not part of the test suite. Run from the repository root:

    LP_NUM_THREADS=2 python3 peers/llvmpipe/bench.py

LP_NUM_THREADS (llvmpipe's rasterizer threads) defaults to 2 when unset.
"""

import argparse
import ctypes
import ctypes.util
import datetime
import gzip
import json
import math
import os
import platform
import statistics
import sys
import time
import tomllib

# llvmpipe reads LP_NUM_THREADS when the screen is created: set it before any GL call.
os.environ.setdefault("LP_NUM_THREADS", "2")

import numpy as np  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DEFAULT_SCENES = [
    os.path.join(REPO, "scenes", name + ".toml")
    for name in ("cornell-bunny-mirror", "office", "conference")
]
VARIANTS = ("depth", "depth+id")
NO_ID = 0xFFFFFFFF

# ---------------------------------------------------------------------------------------
# Scene loading (TOML + OBJ)
# ---------------------------------------------------------------------------------------

MESH_KEYS = {"path", "scale", "rotate", "translate", "exclude_materials"}


def load_obj(path):
    """Positions (n, 3) float64, triangles (m, 3) int64 and each triangle's material name.

    Reads `v`, `f` and `usemtl` lines only; polygons are triangulated as fans around
    their first vertex; negative (relative) indices are resolved; everything else
    (normals, texture coordinates, groups, ...) is ignored.
    """
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt", encoding="utf-8", errors="replace") as fh:
        lines = fh.read().splitlines()
    verts = []
    tris = []
    tri_mat = []
    mat_names = []
    mat_index = {}
    cur_mat = -1
    for line in lines:
        if line.startswith("v "):
            p = line.split()
            verts.append((p[1], p[2], p[3]))
        elif line.startswith("f "):
            nv = len(verts)
            idx = []
            for tok in line.split()[1:]:
                i = int(tok.split("/", 1)[0])
                idx.append(i - 1 if i > 0 else nv + i)
            for k in range(1, len(idx) - 1):
                tris.append((idx[0], idx[k], idx[k + 1]))
                tri_mat.append(cur_mat)
        elif line.startswith("usemtl"):
            p = line.split(None, 1)
            name = p[1].strip() if len(p) > 1 else ""
            if name not in mat_index:
                mat_index[name] = len(mat_names)
                mat_names.append(name)
            cur_mat = mat_index[name]
    v = np.array(verts, dtype=np.float64).reshape(-1, 3)
    t = np.array(tris, dtype=np.int64).reshape(-1, 3)
    if t.size and (t.min() < 0 or t.max() >= len(v)):
        raise ValueError(f"{path}: face index out of range")
    return v, t, np.array(tri_mat, dtype=np.int64), mat_names


def euler_xyz_extrinsic(deg):
    """R = Rz(rz) * Ry(ry) * Rx(rx), angles in degrees (docs/scene-format.md)."""
    rx, ry, rz = (math.radians(a) for a in deg)
    cx, sx, cy, sy, cz, sz = (math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry),
                              math.cos(rz), math.sin(rz))
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def load_scene(toml_path):
    with open(toml_path, "rb") as fh:
        doc = tomllib.load(fh)
    base = os.path.dirname(os.path.abspath(toml_path))
    name = doc.get("name", os.path.splitext(os.path.basename(toml_path))[0])
    meshes = doc.get("mesh", [])
    if not meshes:
        raise ValueError(f"{toml_path}: no [[mesh]]")
    all_v, all_t = [], []
    notes = []
    offset = 0
    for m in meshes:
        unknown = set(m) - MESH_KEYS
        if unknown:
            raise ValueError(f"{toml_path}: mesh keys this script does not handle: {sorted(unknown)}")
        path = m["path"] if os.path.isabs(m["path"]) else os.path.join(base, m["path"])
        v, t, tm, mat_names = load_obj(path)
        excl = m.get("exclude_materials", [])
        if excl:
            missing = [e for e in excl if e not in mat_names]
            if missing:
                raise ValueError(f"{toml_path}: exclude_materials {missing} not in {path}")
            bad = [mat_names.index(e) for e in excl]
            keep = ~np.isin(tm, bad)
            notes.append(f"{os.path.basename(path)}: left out {int((~keep).sum())} triangles "
                         f"of {excl}")
            t = t[keep]
        if any(k in m for k in ("scale", "rotate", "translate")):
            s = m.get("scale", 1.0)
            s = np.array([s, s, s] if isinstance(s, (int, float)) else s, dtype=np.float64)
            R = euler_xyz_extrinsic(m.get("rotate", [0.0, 0.0, 0.0]))
            T = np.array(m.get("translate", [0.0, 0.0, 0.0]), dtype=np.float64)
            v = (v * s) @ R.T + T  # M = T * R * S
            notes.append(f"{os.path.basename(path)}: transform applied "
                         f"(scale {m.get('scale', 1.0)}, rotate {m.get('rotate', [0, 0, 0])}, "
                         f"translate {m.get('translate', [0, 0, 0])})")
        all_v.append(v)
        all_t.append(t + offset)
        offset += len(v)
    verts = np.concatenate(all_v)
    tris = np.concatenate(all_t)
    lights = [np.array(l["position"], dtype=np.float64) for l in doc.get("light", [])]
    return {"name": name, "path": toml_path, "verts": verts, "tris": tris,
            "lights": lights, "notes": notes}


# ---------------------------------------------------------------------------------------
# Cube-map matrices
# ---------------------------------------------------------------------------------------

# The usual GL cube-map faces: +X, -X, +Y, -Y, +Z, -Z with their up vectors.
FACES = [
    ((1, 0, 0), (0, -1, 0)),
    ((-1, 0, 0), (0, -1, 0)),
    ((0, 1, 0), (0, 0, 1)),
    ((0, -1, 0), (0, 0, -1)),
    ((0, 0, 1), (0, -1, 0)),
    ((0, 0, -1), (0, -1, 0)),
]


def face_basis(face):
    fwd, up = (np.array(x, dtype=np.float64) for x in FACES[face])
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, fwd)
    return fwd, right, cam_up


def face_mvp(eye, face, near, far):
    fwd, right, cam_up = face_basis(face)
    V = np.eye(4)
    V[0, :3], V[0, 3] = right, -right @ eye
    V[1, :3], V[1, 3] = cam_up, -cam_up @ eye
    V[2, :3], V[2, 3] = -fwd, fwd @ eye
    P = np.zeros((4, 4))
    P[0, 0] = P[1, 1] = 1.0  # 1 / tan(45 degrees)
    P[2, 2] = (far + near) / (near - far)
    P[2, 3] = 2.0 * far * near / (near - far)
    P[3, 2] = -1.0
    return P @ V


# ---------------------------------------------------------------------------------------
# Raw GL entry points for what moderngl does not expose (cube-face attachments,
# integer clears, read-back of an integer attachment)
# ---------------------------------------------------------------------------------------

GL_FRAMEBUFFER = 0x8D40
GL_FRAMEBUFFER_COMPLETE = 0x8CD5
GL_DEPTH_ATTACHMENT = 0x8D00
GL_COLOR_ATTACHMENT0 = 0x8CE0
GL_TEXTURE_CUBE_MAP = 0x8513
GL_TEXTURE_CUBE_MAP_POSITIVE_X = 0x8515
GL_NONE = 0
GL_COLOR = 0x1800
GL_DEPTH = 0x1801
GL_DEPTH_COMPONENT = 0x1902
GL_FLOAT = 0x1406
GL_UNSIGNED_INT = 0x1405
GL_RED_INTEGER = 0x8D94
GL_TEXTURE_DEPTH_SIZE = 0x884A
GL_TEXTURE_INTERNAL_FORMAT = 0x1003
GL_PACK_ALIGNMENT = 0x0D05


class RawGL:
    def __init__(self):
        lib = ctypes.CDLL(ctypes.util.find_library("GL") or "libGL.so.1")
        u, i, p = ctypes.c_uint, ctypes.c_int, ctypes.c_void_p

        def fn(name, *args, restype=None):
            f = getattr(lib, name)
            f.argtypes = list(args)
            f.restype = restype
            return f

        self.GenFramebuffers = fn("glGenFramebuffers", i, p)
        self.DeleteFramebuffers = fn("glDeleteFramebuffers", i, p)
        self.BindFramebuffer = fn("glBindFramebuffer", u, u)
        self.FramebufferTexture2D = fn("glFramebufferTexture2D", u, u, u, u, i)
        self.CheckFramebufferStatus = fn("glCheckFramebufferStatus", u, restype=u)
        self.DrawBuffer = fn("glDrawBuffer", u)
        self.ReadBuffer = fn("glReadBuffer", u)
        self.Viewport = fn("glViewport", i, i, i, i)
        self.ClearBufferfv = fn("glClearBufferfv", u, i, p)
        self.ClearBufferuiv = fn("glClearBufferuiv", u, i, p)
        self.ReadPixels = fn("glReadPixels", i, i, i, i, u, u, p)
        self.PixelStorei = fn("glPixelStorei", u, i)
        self.BindTexture = fn("glBindTexture", u, u)
        self.GetTexLevelParameteriv = fn("glGetTexLevelParameteriv", u, i, u, p)
        self.GetError = fn("glGetError", restype=u)
        self._one = (ctypes.c_float * 1)(1.0)
        self._noid = (ctypes.c_uint * 4)(NO_ID, NO_ID, NO_ID, NO_ID)

    def check(self, what):
        err = self.GetError()
        if err:
            raise RuntimeError(f"GL error 0x{err:04x} after {what}")

    def cube_fbos(self, depth_glo, color_glo):
        """Six framebuffers, one per cube face of the given texture(s)."""
        ids = (ctypes.c_uint * 6)()
        self.GenFramebuffers(6, ids)
        for f in range(6):
            self.BindFramebuffer(GL_FRAMEBUFFER, ids[f])
            target = GL_TEXTURE_CUBE_MAP_POSITIVE_X + f
            self.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, target, depth_glo, 0)
            if color_glo is None:
                self.DrawBuffer(GL_NONE)
                self.ReadBuffer(GL_NONE)
            else:
                self.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, target,
                                          color_glo, 0)
                self.DrawBuffer(GL_COLOR_ATTACHMENT0)
                self.ReadBuffer(GL_COLOR_ATTACHMENT0)
            status = self.CheckFramebufferStatus(GL_FRAMEBUFFER)
            if status != GL_FRAMEBUFFER_COMPLETE:
                raise RuntimeError(f"framebuffer of face {f} incomplete: 0x{status:04x}")
        self.check("cube framebuffers")
        return ids

    def delete_fbos(self, ids):
        self.BindFramebuffer(GL_FRAMEBUFFER, 0)
        self.DeleteFramebuffers(len(ids), ids)

    def begin_face(self, fbo, size, with_id):
        self.BindFramebuffer(GL_FRAMEBUFFER, fbo)
        self.Viewport(0, 0, size, size)
        if with_id:
            self.ClearBufferuiv(GL_COLOR, 0, self._noid)
        self.ClearBufferfv(GL_DEPTH, 0, self._one)

    def read_face(self, fbo, size, with_id):
        self.BindFramebuffer(GL_FRAMEBUFFER, fbo)
        self.PixelStorei(GL_PACK_ALIGNMENT, 4)
        depth = np.empty((size, size), dtype=np.float32)
        self.ReadPixels(0, 0, size, size, GL_DEPTH_COMPONENT, GL_FLOAT,
                        depth.ctypes.data_as(ctypes.c_void_p))
        ids = None
        if with_id:
            ids = np.empty((size, size), dtype=np.uint32)
            self.ReadPixels(0, 0, size, size, GL_RED_INTEGER, GL_UNSIGNED_INT,
                            ids.ctypes.data_as(ctypes.c_void_p))
        self.check("read-back")
        return depth, ids

    def tex_level_param(self, glo, pname):
        out = ctypes.c_int(0)
        self.BindTexture(GL_TEXTURE_CUBE_MAP, glo)
        self.GetTexLevelParameteriv(GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, pname, ctypes.byref(out))
        self.BindTexture(GL_TEXTURE_CUBE_MAP, 0)
        return out.value


VS = """
#version 330 core
uniform mat4 mvp;
in vec3 in_pos;
void main() { gl_Position = mvp * vec4(in_pos, 1.0); }
"""
FS_DEPTH = """
#version 330 core
void main() {}
"""
FS_ID = """
#version 330 core
layout(location = 0) out uint out_id;
void main() { out_id = uint(gl_PrimitiveID); }
"""


# ---------------------------------------------------------------------------------------
# Check (not timed): the maps agree with the geometry
# ---------------------------------------------------------------------------------------

def check_maps(scene, eye, near, far, size, faces_depth, faces_id, faces_depth_only, rng):
    """Per texel hit: the triangle id is valid, the ray through the texel centre meets that
    triangle (barycentric test with a small tolerance), and the depth buffer's distance
    matches the ray's distance to the triangle's plane. Also: depth-only and depth+id
    depths are identical."""
    verts, tris = scene["verts"], scene["tris"]
    ntri = len(tris)
    hits = 0
    texels = 0
    same_depth = True
    rel_errs = []
    inside = 0
    checked = 0
    for f in range(6):
        depth, ids, depth_only = faces_depth[f], faces_id[f], faces_depth_only[f]
        texels += depth.size
        same_depth &= bool(np.array_equal(depth, depth_only))
        hit = ids != NO_ID
        if not np.array_equal(hit, depth < 1.0):
            raise RuntimeError(f"face {f}: id coverage and depth coverage differ")
        hits += int(hit.sum())
        if hit.any() and int(ids[hit].max()) >= ntri:
            raise RuntimeError(f"face {f}: triangle id out of range")
        ys, xs = np.nonzero(hit)
        if len(ys) == 0:
            continue
        pick = rng.choice(len(ys), size=min(2000, len(ys)), replace=False)
        ys, xs = ys[pick], xs[pick]
        fwd, right, cam_up = face_basis(f)
        nx = (xs + 0.5) / size * 2.0 - 1.0
        ny = (ys + 0.5) / size * 2.0 - 1.0  # row 0 of glReadPixels is the bottom row
        d = fwd[None, :] + nx[:, None] * right[None, :] + ny[:, None] * cam_up[None, :]
        z_ndc = 2.0 * depth[ys, xs].astype(np.float64) - 1.0
        z_eye = 2.0 * far * near / ((far + near) - z_ndc * (far - near))
        t_depth = z_eye  # d has unit component along fwd, so t = z_eye along d
        tri = tris[ids[ys, xs].astype(np.int64)]
        a, b, c = verts[tri[:, 0]], verts[tri[:, 1]], verts[tri[:, 2]]
        e1, e2 = b - a, c - a
        n = np.cross(e1, e2)
        denom = np.einsum("ij,ij->i", n, d)
        ok = np.abs(denom) > 1e-30
        t_plane = np.einsum("ij,ij->i", n, a - eye) / np.where(ok, denom, 1.0)
        rel_errs.append(np.abs(t_depth[ok] - t_plane[ok]) / np.abs(t_plane[ok]))
        # barycentric coordinates of the plane point
        q = eye + d * t_plane[:, None] - a
        d00 = np.einsum("ij,ij->i", e1, e1)
        d01 = np.einsum("ij,ij->i", e1, e2)
        d11 = np.einsum("ij,ij->i", e2, e2)
        d20 = np.einsum("ij,ij->i", q, e1)
        d21 = np.einsum("ij,ij->i", q, e2)
        den = d00 * d11 - d01 * d01
        den = np.where(np.abs(den) > 0, den, 1.0)
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        u = 1.0 - v - w
        tol = 1e-3
        inside += int(((u >= -tol) & (v >= -tol) & (w >= -tol) & ok).sum())
        checked += len(ys)
    errs = np.concatenate(rel_errs) if rel_errs else np.zeros(0)
    return {
        "coverage": hits / texels,
        "checked_texels": checked,
        "ray_meets_id_triangle": inside / max(checked, 1),
        "depth_vs_plane_rel_err_median": float(np.median(errs)) if errs.size else 0.0,
        "depth_vs_plane_rel_err_p99": float(np.quantile(errs, 0.99)) if errs.size else 0.0,
        "depth_only_equals_depth_id": same_depth,
    }


# ---------------------------------------------------------------------------------------
# Benchmark
# ---------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", default=DEFAULT_SCENES, help="scene TOML files")
    ap.add_argument("--resolutions", type=int, nargs="+", default=[512, 1024, 2048])
    ap.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    ap.add_argument("--reps", type=int, default=7, help="timed repetitions per light (>= 1)")
    ap.add_argument("--warmup", type=int, default=1, help="untimed repetitions per light first")
    ap.add_argument("--max-lights", type=int, default=0, help="use only the first N lights (0: all)")
    ap.add_argument("--near", type=float, default=1e-3, help="near plane / bounding-box diagonal")
    ap.add_argument("--far", type=float, default=2.0, help="far plane / bounding-box diagonal")
    ap.add_argument("--no-check", action="store_true", help="skip the correctness check")
    ap.add_argument("--json", help="also write all results (per light) to this JSON file")
    args = ap.parse_args()

    import moderngl

    ctx = moderngl.create_standalone_context(backend="egl", require=330)
    renderer = ctx.info["GL_RENDERER"]
    version = ctx.info["GL_VERSION"]
    if "llvmpipe" not in renderer:
        sys.exit(f"renderer is not llvmpipe: {renderer!r}")
    gl = RawGL()
    ctx.enable_only(moderngl.DEPTH_TEST)  # no face culling, no blending
    ctx.depth_func = "<"

    cpu = platform.processor() or "?"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load_start = os.getloadavg()
    header = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "renderer": renderer,
        "gl_version": version,
        "vendor": ctx.info["GL_VENDOR"],
        "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS"),
        "cpu": cpu,
        "nproc": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "moderngl": moderngl.__version__,
        "reps": args.reps,
        "warmup": args.warmup,
        "load_avg_start": [round(x, 2) for x in load_start],
    }
    print(f"GL_RENDERER    {renderer}")
    print(f"GL_VERSION     {version}")
    print(f"LP_NUM_THREADS {header['LP_NUM_THREADS']}")
    print(f"CPU            {cpu} ({os.cpu_count()} logical cores)")
    print(f"numpy {np.__version__}, moderngl {moderngl.__version__}, Python {header['python']}")
    print(f"repetitions    {args.warmup} warm-up + {args.reps} timed per light; "
          f"load average at start {header['load_avg_start']}")
    sys.stdout.flush()

    prog = {
        "depth": ctx.program(vertex_shader=VS, fragment_shader=FS_DEPTH),
        "depth+id": ctx.program(vertex_shader=VS, fragment_shader=FS_ID),
    }
    rng = np.random.default_rng(1)
    rows = []
    checks = []
    for scene_path in args.scenes:
        t_load = time.perf_counter()
        scene = load_scene(scene_path)
        t_load = time.perf_counter() - t_load
        verts, tris, lights = scene["verts"], scene["tris"], scene["lights"]
        if args.max_lights:
            lights = lights[: args.max_lights]
        lo, hi = verts[tris.reshape(-1)].min(0), verts[tris.reshape(-1)].max(0)
        diag = float(np.linalg.norm(hi - lo))
        near, far = args.near * diag, args.far * diag
        print(f"\n{scene['name']}: {len(tris)} triangles, {len(verts)} vertices, "
              f"{len(lights)} lights, bbox diagonal {diag:.4g}, near {near:.4g}, far {far:.4g} "
              f"(loaded in {t_load:.1f} s)")
        for note in scene["notes"]:
            print(f"  {note}")
        if not scene["notes"]:
            print("  meshes: no transform, no exclusion in the scene file")
        vbo = ctx.buffer(verts.astype("f4").tobytes())
        ibo = ctx.buffer(tris.astype("u4").tobytes())
        vao = {v: ctx.vertex_array(prog[v], [(vbo, "3f", "in_pos")], index_buffer=ibo,
                                   index_element_size=4) for v in VARIANTS}
        mvps = [[face_mvp(eye, f, near, far).T.astype("f4").tobytes() for f in range(6)]
                for eye in lights]
        for size in args.resolutions:
            depth_tex = ctx.depth_texture_cube((size, size))
            id_tex = ctx.texture_cube((size, size), 1, dtype="u4")
            fbos = {"depth": gl.cube_fbos(depth_tex.glo, None),
                    "depth+id": gl.cube_fbos(depth_tex.glo, id_tex.glo)}
            depth_bits = gl.tex_level_param(depth_tex.glo, GL_TEXTURE_DEPTH_SIZE)

            def draw(variant, li):
                fb, pr, va, m = fbos[variant], prog[variant], vao[variant], mvps[li]
                with_id = variant == "depth+id"
                for f in range(6):
                    gl.begin_face(fb[f], size, with_id)
                    pr["mvp"].write(m[f])
                    va.render(moderngl.TRIANGLES)

            if not args.no_check and size == args.resolutions[0]:
                draw("depth", 0)
                ctx.finish()
                d_only = [gl.read_face(fbos["depth"][f], size, False)[0] for f in range(6)]
                draw("depth+id", 0)
                ctx.finish()
                got = [gl.read_face(fbos["depth+id"][f], size, True) for f in range(6)]
                chk = check_maps(scene, lights[0], near, far, size, [g[0] for g in got],
                                 [g[1] for g in got], d_only, rng)
                chk.update(scene=scene["name"], light=0, resolution=size,
                           depth_bits=depth_bits)
                checks.append(chk)
                print(f"  check (light 0, {size}, {depth_bits}-bit depth): coverage "
                      f"{chk['coverage']:.3f}, ray meets id's triangle "
                      f"{100 * chk['ray_meets_id_triangle']:.2f} % of {chk['checked_texels']} "
                      f"texels, |depth - plane| / distance median "
                      f"{chk['depth_vs_plane_rel_err_median']:.1e} p99 "
                      f"{chk['depth_vs_plane_rel_err_p99']:.1e}, depth maps equal: "
                      f"{chk['depth_only_equals_depth_id']}")
            gl.check("setup")

            for variant in args.variants:
                per_light = []
                for li in range(len(lights)):
                    for _ in range(args.warmup):
                        draw(variant, li)
                        ctx.finish()
                    times = []
                    for _ in range(args.reps):
                        t0 = time.perf_counter()
                        draw(variant, li)
                        ctx.finish()
                        times.append((time.perf_counter() - t0) * 1e3)
                    per_light.append({"light": li, "median_ms": statistics.median(times),
                                      "min_ms": min(times), "max_ms": max(times),
                                      "times_ms": [round(t, 3) for t in times]})
                gl.check("drawing")
                meds = [p["median_ms"] for p in per_light]
                row = {
                    "scene": scene["name"], "triangles": len(tris), "lights": len(lights),
                    "resolution": size, "variant": variant, "depth_bits": depth_bits,
                    "median_ms_per_light": statistics.median(meds),
                    "ms_per_face": statistics.median(meds) / 6.0,
                    "light_medians_min_ms": min(meds), "light_medians_max_ms": max(meds),
                    "all_lights_ms": sum(meds), "per_light": per_light,
                }
                rows.append(row)
                print(f"  {size:5d} {variant:9s} median {row['median_ms_per_light']:9.2f} ms "
                      f"per light (6 faces), {row['ms_per_face']:8.2f} ms per face; per-light "
                      f"medians {min(meds):.2f}-{max(meds):.2f} ms, all lights "
                      f"{sum(meds):.1f} ms")
                sys.stdout.flush()
            gl.delete_fbos(fbos["depth"])
            gl.delete_fbos(fbos["depth+id"])
            depth_tex.release()
            id_tex.release()
        for v in vao.values():
            v.release()
        vbo.release()
        ibo.release()

    header["load_avg_end"] = [round(x, 2) for x in os.getloadavg()]
    print(f"\nload average at end {header['load_avg_end']}")
    print("\n| scene | triangles | lights | resolution | variant | median ms per light (6 faces) "
          "| ms per face |")
    print("| --- | ---: | ---: | ---: | --- | ---: | ---: |")
    for r in rows:
        print(f"| {r['scene']} | {r['triangles']:,} | {r['lights']} | {r['resolution']} | "
              f"{r['variant']} | {r['median_ms_per_light']:.1f} | {r['ms_per_face']:.2f} |")
    print("\n| scene | resolution | variant | per-light medians min-max ms | all lights ms |")
    print("| --- | ---: | --- | ---: | ---: |")
    for r in rows:
        print(f"| {r['scene']} | {r['resolution']} | {r['variant']} | "
              f"{r['light_medians_min_ms']:.1f}-{r['light_medians_max_ms']:.1f} | "
              f"{r['all_lights_ms']:.1f} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"header": header, "checks": checks, "rows": rows}, fh, indent=1)
        print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
