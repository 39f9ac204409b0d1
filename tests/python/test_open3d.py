"""Interop with a real client, Open3D (Debian's python3-open3d): a model read by Open3D (a TriangleMesh
with triangle_uvs and its texture) through optimize_arrays, loaded back into Open3D, written by Open3D's
own writer and measured by tightex's measure: nothing lost or flipped, the colours kept."""
import json
import os
import subprocess

import numpy as np
import pytest

o3d = pytest.importorskip("open3d", reason="Debian's python3-open3d is not installed")


def tightex_cli():
    build = os.environ.get("TIGHTEX_BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
    return os.path.join(build, "tightex")


def open3d_scan(folder):
    """An OBJ that Open3D writes: its UV sphere (charts of its own uv map) with a gradient texture.
    Open3D writes 6 significant digits, so the model tightex is compared with is the one Open3D wrote."""
    sphere = o3d.geometry.TriangleMesh.create_sphere(radius=1.0, resolution=24, create_uv_map=True)
    y, x = np.mgrid[0:256, 0:256]
    texture = np.stack([x, y, (x * y) // 256], axis=-1).astype(np.uint8)
    sphere.textures = [o3d.geometry.Image(texture)]
    sphere.triangle_material_ids = o3d.utility.IntVector([0] * len(sphere.triangles))
    folder.mkdir()
    model = folder / "sphere.obj"
    assert o3d.io.write_triangle_mesh(str(model), sphere)
    return model


def test_open3d_mesh_round_trip(tightex, tmp_path):
    model = open3d_scan(tmp_path / "in")
    mesh = o3d.io.read_triangle_mesh(str(model), enable_post_processing=True)
    assert mesh.has_triangle_uvs() and len(mesh.textures) == 1
    out = tightex.optimize_arrays(np.asarray(mesh.vertices), np.asarray(mesh.triangles),
                                  np.asarray(mesh.triangle_uvs).reshape(-1, 3, 2),
                                  # Open3D holds a texture read from OBJ bottom row first: flipped to the file's rows.
                                  [np.asarray(t)[::-1] for t in mesh.textures], size=256)
    assert out["report"]["metrics"]["lost_triangles"] == 0 and out["report"]["metrics"]["flipped"] == 0

    back = o3d.geometry.TriangleMesh()
    back.vertices = o3d.utility.Vector3dVector(out["positions"])
    back.triangles = o3d.utility.Vector3iVector(out["faces"].astype(np.int32))
    back.triangle_uvs = o3d.utility.Vector2dVector(out["uvs"].reshape(-1, 2))
    back.triangle_material_ids = o3d.utility.IntVector(out["material_ids"].astype(np.int32))
    back.textures = [o3d.geometry.Image(np.ascontiguousarray(image[::-1, :, :3])) for image in out["images"]]
    assert len(back.triangles) == len(mesh.triangles)
    written = tmp_path / "back" / "sphere.obj"
    written.parent.mkdir()
    assert o3d.io.write_triangle_mesh(str(written), back)

    if not os.access(tightex_cli(), os.X_OK):
        pytest.skip("the tightex command is not built beside the module")
    measured = json.loads(subprocess.run([tightex_cli(), "measure", str(model), str(written)], check=True,
                                         capture_output=True, text=True).stdout)
    assert measured["lost_triangles"] == 0 and measured["flipped"] == 0
    assert measured["surface_psnr_db"] > 30, measured["surface_psnr_db"]
