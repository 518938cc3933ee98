"""The Python package on real meshes: zero-copy views that keep their file alive, levels equal to
tomextract's, extraction into caller arrays, building and writing from numpy, every importer,
reports equal to tombuild's JSON report, errors as tom.Error subclasses, the GIL released.

Run by ctest with PYTHONPATH=build/python, TOM_TOOLS (tombuild, tomextract) and TOM_DATA_DIR."""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import tom

TOOLS = os.environ["TOM_TOOLS"]
DATA = os.environ["TOM_DATA_DIR"]


def tombuild(tmp_path, source, *options):
    subprocess.run([f"{TOOLS}/tombuild", source, "-o", str(tmp_path), "-q", *options], check=True)
    return tmp_path / (os.path.splitext(os.path.basename(source))[0] + ".tom")


def tomextract_faces(path, fraction, tmp_path):
    obj = tmp_path / "level.obj"
    subprocess.run([f"{TOOLS}/tomextract", str(path), "--fraction", str(fraction), "-o", str(obj)], check=True, capture_output=True)
    faces = [line.split()[1:] for line in obj.read_text().splitlines() if line.startswith("f ")]
    return np.array([[int(c.split("//")[0]) - 1 for c in f] for f in faces], dtype=np.int64)


def grid(n, bump=0.1):
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    x, y = i.ravel() / (n - 1), j.ravel() / (n - 1)
    positions = np.stack([x, y, bump * np.sin(6 * x) * np.cos(4 * y)], axis=1).astype(np.float32)
    a = (j[:-1, :-1] * n + i[:-1, :-1]).ravel()
    triangles = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)]).astype(np.uint32)
    return positions, triangles


@pytest.fixture(scope="module")
def bunny(tmp_path_factory):
    return tombuild(tmp_path_factory.mktemp("bunny"), f"{DATA}/meshes/bunny00.off")


def test_views_are_zero_copy_read_only_and_keep_the_file_alive(bunny):
    f = tom.open(str(bunny))
    mesh = f.meshes[0]
    assert (mesh.vertex_count, len(f)) == (mesh.positions.shape[0], 1)
    a, b = mesh.positions, mesh.positions
    assert np.shares_memory(a, b)  # both views of the mapping, not copies
    assert a.dtype == np.float32 and a.shape == (mesh.vertex_count, 3) and mesh.normals.shape == a.shape
    assert mesh.triangles.shape == (mesh.triangle_count, 3) and mesh.triangles.dtype == np.uint16
    with pytest.raises(ValueError):
        a[0, 0] = 1.0
    first = a[:4].copy()
    del f, mesh, b
    import gc
    gc.collect()
    assert np.array_equal(a[:4], first)  # the array keeps the mapping alive
    # the stored order: every removed vertex's substitute comes before it
    mesh = tom.open(str(bunny)).meshes[0]
    s = mesh.substitute.astype(np.int64)
    k = np.arange(mesh.vertex_count)
    assert np.all(s[mesh.min_vertex_count:] < k[mesh.min_vertex_count:]) and np.all(s[:mesh.min_vertex_count] == k[:mesh.min_vertex_count])


@pytest.mark.parametrize("fraction", [1.0, 0.1, 0.01])
def test_levels_are_tomextracts_index_for_index(bunny, tmp_path, fraction):
    mesh = tom.open(str(bunny)).meshes[0]
    indices, n = mesh.extract(fraction=fraction)
    expected = tomextract_faces(bunny, fraction, tmp_path)
    assert indices.shape == expected.shape and np.array_equal(indices.astype(np.int64), expected)
    assert indices.max() < n and len(indices) == mesh.active_triangles(n)


def test_a_streamed_file_and_its_prefixes_open_as_tomextract_decodes_them(bunny, tmp_path):
    streamed = tombuild(tmp_path, f"{DATA}/meshes/bunny00.off", "--stream")
    info = json.loads(subprocess.run([f"{TOOLS}/tominfo", "--json", str(streamed)], check=True, capture_output=True).stdout)
    chunk = info["stream"]["chunks"][5]
    prefix = tom.open(str(streamed), byte_limit=chunk["end_byte"] + 10).meshes[0]
    assert (prefix.vertex_count, prefix.triangle_count) == (chunk["vertices"], chunk["triangles"])
    indices, n = prefix.extract(vertices=chunk["vertices"])
    whole = tom.open(str(streamed)).meshes[0]
    expected, _ = whole.extract(vertices=chunk["vertices"])
    assert n == chunk["vertices"] and np.array_equal(indices, expected)
    assert whole.triangle_count == info["meshes"][0]["triangles"]
    # the ordinary file's level there (its vertices renumbered within the chunks: cli_test.sh
    # measures the two surfaces' distance)
    level, _ = tom.open(str(bunny)).meshes[0].extract(vertices=chunk["vertices"])
    assert len(level) == len(indices) == chunk["triangles"]
    with pytest.raises(tom.ArgumentError, match="byte limit applies only to streams"):
        tom.open(str(bunny), byte_limit=1000)


def test_refit_is_tomextract_refits_level_and_moves_within_it(bunny, tmp_path):
    mesh = tom.open(str(bunny)).meshes[0]
    indices, n = mesh.extract(fraction=0.1)
    level = mesh.refit(fraction=0.1)
    positions = level["positions"]
    assert positions.shape == (n, 3) and positions.dtype == np.float32
    assert ("normals" in level) == (mesh.normals is not None) and "uv" not in level  # bunny00.off: positions alone
    obj = tmp_path / "refit.obj"
    subprocess.run([f"{TOOLS}/tomextract", str(bunny), "--fraction", "0.1", "--refit", "-o", str(obj)], check=True, capture_output=True)
    written = np.array([[float(x) for x in line.split()[1:4]] for line in obj.read_text().splitlines() if line.startswith("v ")], np.float32)
    assert np.allclose(written, positions, rtol=0, atol=1e-6 * np.abs(positions).max())
    # most live points stand for removed vertices and move; none by more than a few of the level's edges
    plain = np.asarray(mesh.positions[:n])
    moved = np.linalg.norm(positions - plain, axis=1)
    edges = np.linalg.norm(plain[indices[:, 0]] - plain[indices[:, 1]], axis=1)
    assert (moved > 0).mean() > 0.5 and moved.max() < 3 * edges.mean(), (moved.max(), edges.mean())


def test_selections_stop_at_the_usable_floor_unless_asked(bunny, tmp_path):
    """tombuild stores where the mean error leaves 1% of the diagonal; a fraction or a triangle
    count stops there, as tomextract does, and goes on to the chain's last level when asked."""
    mesh = tom.open(str(bunny)).meshes[0]
    assert mesh.min_vertex_count < mesh.usable_floor < mesh.vertex_count // 100
    assert mesh.vertex_count_for(fraction=0.0) == mesh.usable_floor == mesh.vertex_count_for(triangles=1)
    assert mesh.vertex_count_for(fraction=0.0, below_floor=True) == mesh.min_vertex_count
    assert mesh.extract(fraction=0.0)[1] == mesh.usable_floor
    assert len(tomextract_faces(bunny, 0.0, tmp_path)) == mesh.active_triangles(mesh.usable_floor)
    assert mesh.extract(vertices=mesh.min_vertex_count)[1] == mesh.min_vertex_count  # an explicit count is taken as asked


def test_extract_into_out_allocates_nothing_and_checks_its_arguments(bunny):
    mesh = tom.open(str(bunny)).meshes[0]
    out32 = np.zeros(3 * mesh.triangle_count, np.uint32)
    out16 = np.zeros(3 * mesh.triangle_count, np.uint16)
    i32, n32 = mesh.extract(vertices=5000, out=out32)
    i16, n16 = mesh.extract(vertices=5000, out=out16)
    assert np.shares_memory(i32, out32) and np.shares_memory(i16, out16)
    assert n32 == n16 == 5000 and np.array_equal(i32, i16)
    t = mesh.active_triangles(5000)
    assert mesh.extract(triangles=t)[1] == mesh.vertex_count_for(triangles=t)
    with pytest.raises(tom.ArgumentError, match="out holds 3 indices"):
        mesh.extract(vertices=5000, out=np.zeros(3, np.uint32))
    with pytest.raises(tom.ArgumentError, match="one of fraction, vertices and triangles"):
        mesh.extract(fraction=0.5, vertices=10)
    with pytest.raises(tom.ArgumentError, match="uint32 or uint16"):
        mesh.extract(out=np.zeros(3 * mesh.triangle_count, np.float32))
    with pytest.raises(tom.ArgumentError, match="outside"):
        mesh.extract(fraction=1.5)


def test_build_from_numpy_is_deterministic_and_round_trips(tmp_path):
    positions, triangles = grid(60)
    one = tom.build(positions, triangles, threads=1, name="grid")
    two = tom.build(positions, triangles, threads=2, name="grid")
    assert tom.serialize([one]) == tom.serialize([two])
    assert one.min_vertex_count < one.vertex_count // 20
    assert tom.serialize([tom.build(tom.Mesh(positions, triangles, name="grid"), threads=2)]) == tom.serialize([one])
    path = tmp_path / "grid.tom"
    tom.write(str(path), [one])
    f = tom.open(str(path))
    assert path.read_bytes() == tom.serialize([one])
    assert np.array_equal(f.meshes[0].positions, one.positions)
    for fraction in (0.5, 0.05):
        assert np.array_equal(f.meshes[0].extract(fraction=fraction)[0], one.extract(fraction=fraction)[0])
    # in place from a bytes object, which the file keeps alive
    image = bytearray(tom.serialize([one], index_size="32"))
    g = tom.open_bytes(image, "image")
    assert g.meshes[0].triangles.dtype == np.uint32 and g.meshes[0].name == "grid"
    # every built position is one of the input's, in resolution order
    assert set(map(tuple, one.positions.tolist())) == set(map(tuple, positions.tolist()))


def test_bad_input_raises_the_librarys_message(tmp_path, bunny):
    data = bytearray(bunny.read_bytes())
    data[len(data) // 2] ^= 0x10
    with pytest.raises(tom.FormatError, match=r"^flipped: byte \d+, .*rule \d+"):
        tom.open_bytes(bytes(data), "flipped")
    with pytest.raises(tom.IoError, match="no-such.tom"):
        tom.open(str(tmp_path / "no-such.tom"))
    with pytest.raises(tom.MeshError, match="IndexOutOfRange.gltf"):
        tom.import_file(f"{DATA}/assimp/glTF2/IndexOutOfRange/IndexOutOfRange.gltf")
    positions, triangles = grid(4)
    with pytest.raises(tom.ArgumentError, match="not one of the 16 vertices"):
        tom.build(positions, np.array([[0, 1, 99]]))
    with pytest.raises(tom.ArgumentError, match="neither 'quadric' nor 'memoryless'"):
        tom.build(positions, triangles, predicate="volume")
    assert issubclass(tom.FormatError, tom.Error) and issubclass(tom.MeshError, tom.Error) and tom.MeshFileError is tom.MeshError


@pytest.mark.parametrize("source,triangles", [
    ("meshes/fandisk.off", 12946),
    ("assimp/OBJ/spider.obj", None),
    ("assimp/PLY/cube.ply", None),
    ("assimp/STL/Spider_ascii.stl", None),
    ("assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf", 12),
    ("assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", 12),
    ("assimp/glTF2/draco/2CylinderEngine.gltf", None),
])
def test_import_file_reads_every_format_tombuild_reads(source, triangles):
    meshes = tom.import_file(f"{DATA}/{source}")
    assert meshes and all(m.positions.shape == (m.vertex_count, 3) and m.triangles.shape == (m.triangle_count, 3) for m in meshes)
    assert all(int(m.triangles.max()) < m.vertex_count for m in meshes)
    if triangles is not None:
        assert sum(m.triangle_count for m in meshes) == triangles


def test_report_has_the_json_reports_figures(tmp_path):
    source = f"{DATA}/meshes/fandisk.off"
    subprocess.run([f"{TOOLS}/tombuild", source, "-o", str(tmp_path), "-q", "--report-json", str(tmp_path)], check=True)
    expected = json.loads((tmp_path / "fandisk.json").read_text())
    expected = expected["meshes"][0] if "meshes" in expected else expected
    mesh = tom.import_file(source)[0]
    r = tom.report(mesh, tom.build(mesh))
    assert r.keys() == expected.keys()
    assert (r["vertices"], r["triangles"], r["bbox_diagonal"]) == (expected["vertices"], expected["triangles"], expected["bbox_diagonal"])
    assert len(r["levels"]) == len(expected["levels"])
    for got, want in zip(r["levels"], expected["levels"]):
        assert (got["vertices"], got["triangles"]) == (want["vertices"], want["triangles"])
        assert got["error"]["hausdorff"] == want["error"]["hausdorff"]
    assert r["memory"] == expected["memory"]


def test_the_gil_is_released_while_building():
    positions, triangles = grid(300)
    start = time.perf_counter()
    tom.build(positions, triangles, threads=1)
    alone = time.perf_counter() - start
    gaps, last = [], None
    worker = threading.Thread(target=lambda: tom.build(positions, triangles, threads=1))
    worker.start()
    while worker.is_alive():
        now = time.perf_counter()
        if last is not None:
            gaps.append(now - last)
        last = now
        time.sleep(0.001)
    worker.join()
    # with the GIL held, this loop would stall for the whole build
    assert alone > 0.05 and max(gaps) < alone / 2


def test_parts_draw_each_material_over_the_level(tmp_path):
    # 2CylinderEngine: four glTF meshes of several primitives, each now one mesh of parts
    f = tom.open(str(tombuild(tmp_path, f"{DATA}/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", "--no-error-curve")))
    multi = [m for m in f.meshes if len(m.parts) > 1]
    assert len(multi) == 4
    for m in multi:
        ranges = m.parts
        assert ranges[0][0] == 0 and sum(count for _, count, _ in ranges) == m.triangle_count
        for fraction in (1.0, 0.25, 0.05):
            level, n = m.extract(fraction=fraction)
            draws = m.draws(fraction=fraction)
            assert [d[2] for d in draws] == [p[2] for p in ranges]  # each part keeps its material
            assert sum(d[1] for d in draws) == len(level)
            for (first, count, _), (_, part_triangles, _) in zip(draws, ranges):
                assert count <= part_triangles
                assert first + count <= len(level)
            assert int(level.max()) < n


def test_an_obj_with_usemtl_builds_with_its_parts_and_locked_borders_stay():
    src = tom.import_file(f"{DATA}/assimp/OBJ/spider.obj")[0]
    built = tom.build(src, threads=1)
    assert [p[2] for p in built.parts] == [0, 1, 2, 3]  # the four usemtl groups, each its material
    positions, triangles = grid(30)
    free = tom.build(positions, triangles, threads=1)
    locked = tom.build(positions, triangles, threads=1, lock_borders=True)
    border = 4 * (30 - 1)
    assert locked.min_vertex_count >= border > free.min_vertex_count


def test_keep_topology_stops_a_closed_mesh_at_a_tetrahedron():
    """cross.off is a closed manifold: kept, it ends as a tetrahedron; by default its last step joins two sheets."""
    src = tom.import_file(f"{DATA}/meshes/cross.off")[0]
    joined = tom.build(src, threads=1)
    kept = tom.build(src, threads=1, keep_topology=True)
    assert kept.min_vertex_count == 4 and kept.active_triangles(4) == 4
    assert joined.min_vertex_count < 4 and joined.active_triangles(joined.min_vertex_count) == 2


def test_an_unindexed_mesh_is_welded_unless_asked_and_simplifies_either_way():
    """Every triangle its own three vertices: welded on import by default, kept with weld=False."""
    positions, triangles = grid(20)
    loose = positions[triangles.reshape(-1)]
    corners = np.arange(len(loose), dtype=np.uint32).reshape(-1, 3)
    welded = tom.build(loose, corners, threads=1)
    kept = tom.build(loose, corners, threads=1, weld=False)
    assert welded.vertex_count == len(positions)
    assert kept.vertex_count == len(loose)
    for built in (welded, kept):
        coarse, _ = built.extract(fraction=0.0)
        assert len(coarse) <= len(triangles) // 10


def test_provenance_names_the_input_tombuild_read(bunny):
    """tombuild's PROV: the tool, the input's size and XXH3-128 digest, the options."""
    prov = json.loads(tom.open(str(bunny)).provenance)
    assert prov["tool"].startswith("tombuild ")
    assert prov["input"]["bytes"] == os.path.getsize(f"{DATA}/meshes/bunny00.off")
    assert prov["input"]["digest"].startswith("xxh3-128:") and len(prov["input"]["digest"]) == 9 + 32
    assert prov["sources"] == [] and prov["options"]["build"]["predicate"] == "quadric"


def glb_image_bytes(path):
    """The bytes of each image in a GLB's binary chunk, read with nothing but struct and json."""
    import struct
    data = open(path, "rb").read()
    json_bytes = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_bytes])
    binary = data[20 + json_bytes + 8:]
    out = []
    for image in doc.get("images", []):
        view = doc["bufferViews"][image["bufferView"]]
        start = view.get("byteOffset", 0)
        out.append((image["mimeType"], binary[start:start + view["byteLength"]]))
    return out


def test_embedded_images_are_stored_byte_for_byte_and_viewed_in_place(tmp_path):
    source = f"{DATA}/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"
    f = tom.open(str(tombuild(tmp_path, source, "--no-error-curve")))
    (mime, expected), = glb_image_bytes(source)
    (image,) = f.images
    assert image["mime_type"] == mime == "image/png"
    assert image["data"].dtype == np.uint8 and bytes(image["data"]) == expected
    with pytest.raises(ValueError):
        image["data"][0] = 0  # a read-only view
    assert np.shares_memory(image["data"], f.images[0]["data"])  # into the mapping, not a copy
    assert f.materials[0]["textures"][0]["image"] == 0 and f.materials[0]["textures"][0]["uri"] == ""
    # a texture whose image is a file keeps its URI and names no stored image
    g = tom.open(str(tombuild(tmp_path, f"{DATA}/assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf", "--no-error-curve")))
    assert g.images == [] and g.materials[0]["textures"][0]["image"] is None
    assert g.materials[0]["textures"][0]["uri"] == "CesiumLogoFlat.png"


def test_carried_streams_are_views_of_the_sources_values(tmp_path):
    f = tom.open(str(tombuild(tmp_path, f"{DATA}/assimp/glTF2/simple_skin/simple_skin.gltf", "--no-error-curve")))
    mesh = f.meshes[0]
    streams = mesh.carried_streams
    assert sorted(streams) == ["JOINTS_0", "WEIGHTS_0"]
    joints, weights = streams["JOINTS_0"], streams["WEIGHTS_0"]
    assert joints.dtype == np.uint16 and joints.shape == (mesh.vertex_count, 4)
    assert weights.dtype == np.float32 and weights.shape == (mesh.vertex_count, 4)
    assert np.allclose(weights.sum(axis=1), 1.0) and joints.max() <= 1  # the sample's two joints, weights summing to one
    with pytest.raises(ValueError):
        weights[0, 0] = 0.5


def test_tcr_governs_a_scene_of_the_bunny_within_its_budget(bunny, tmp_path):
    """tom.tcr: 24 copies of the bunny under the frame governor on a renderer 1.3x slower than
    calibrated; every drawn object's level extracts as reported; bad input raises tom errors."""
    model = tom.tcr.CostModel()
    model.t_init_ms = model.t_final_ms = 0.5
    model.t_setup_ms, model.t_tri_ms, model.t_vert_ms, model.t_pix_ms = 0.02, 2e-5, 1e-5, 1e-6
    model.safety_ms, model.noise_rel = 0.2, 0.03
    f = tom.open(str(bunny))
    rt = tom.tcr.Runtime(model, "exact")
    for i in range(24):
        t = np.eye(4, dtype=np.float32)
        t[0, 3], t[1, 3], t[2, 3] = 0.3 * (i % 6) - 0.75, 0.3 * (i // 6) - 0.45, -3.0
        assert rt.add_object(f.meshes[0], t) == i
    governor = tom.tcr.FrameGovernor(rt, model, budget_ms=8.0)
    renderer = tom.tcr.SimulatedRenderer(0.03, slowdown=1.3)
    view = tom.tcr.look_at([0, 0, 0], [0, 0, -1], [0, 1, 0])
    projection = tom.tcr.perspective(1.0, 4 / 3, 0.1, 100.0)
    times = []
    for frame in range(80):
        warm = governor.warming_up
        reserve = governor.planning_reserve_ms
        report = governor.plan_frame(view, projection, 800, 600)
        drawn = 0
        for i in range(len(rt)):
            o = rt.object(i)
            indices, n = rt.indices(i)
            assert len(indices) == (o["triangles"] if o["drawn"] else 0)
            if o["drawn"]:
                assert n == o["vertices"] and indices.max() < n
                drawn += len(indices)
        assert drawn == report["triangles"]
        render_ms = renderer.frame_ms(report, governor.model)
        governor.frame_done(0.0, render_ms)
        if not warm and frame >= 24:
            times.append(reserve + render_ms)
    times = np.array(times)
    assert np.mean(times > 1.1 * 8.0) <= 0.05 and 0.75 * 8.0 < times.mean() < 1.05 * 8.0, times
    with pytest.raises(tom.ArgumentError, match="selector 'fastest'"):
        tom.tcr.Runtime(model, "fastest")
    with pytest.raises(tom.ArgumentError, match="4x4"):
        rt.add_object(f.meshes[0], np.eye(3))
    with pytest.raises(tom.ArgumentError, match="object 99"):
        rt.object(99)
    bad = tmp_path / "calibration.txt"
    bad.write_text("t_init_ms 0.5\nt_tri_ms lots\n")
    with pytest.raises(tom.ParseError, match="calibration.txt"):
        tom.tcr.read_cost_model(str(bad))


class GeometryRenderer:
    """Frames of 0.3 ms, plus per draw 0.005 ms, 5e-5 ms a triangle and 4e-5 ms a distinct vertex
    (half that flat-shaded); no texture mapping, no imposters."""
    width, height = 640, 480

    def __init__(self):
        self.frames = 0

    def time_frame(self, camera, draws, way):
        if way == "textured":
            return -1.0
        assert camera["view"].shape == (4, 4) and camera["width"] == 640
        scale = 0.5 if way == "flat" else 1.0
        t = 0.3
        for d in draws:
            assert d["model"].shape == (4, 4) and d["indices"].dtype == np.uint32
            t += 0.005 + scale * (5e-5 * (len(d["indices"]) // 3) + 4e-5 * len(np.unique(d["indices"])))
        self.frames += 1
        return t


def test_tcr_calibrate_recovers_a_python_renderers_costs(bunny, tmp_path):
    """tom.tcr.calibrate drives a Python renderer, fits its costs, writes the file; what the
    renderer raises reaches the caller."""
    f = tom.open(str(bunny))
    renderer = GeometryRenderer()
    path = tmp_path / "python.calibration"
    m = tom.tcr.calibrate(renderer, [f.meshes[0]], str(path))
    assert renderer.frames > 100
    assert abs(m.t_init_ms + m.t_final_ms - 0.3) < 1e-6
    # vertices are about half the triangles: the fit may split the cost between them
    assert abs(m.t_tri_ms + 0.5 * m.t_vert_ms - (5e-5 + 0.5 * 4e-5)) < 0.1 * 7e-5, (m.t_tri_ms, m.t_vert_ms)
    assert abs(m.flat_t_tri_ms + 0.5 * m.flat_t_vert_ms - 0.5 * 7e-5) < 0.1 * 3.5e-5
    assert m.textured_t_tri_ms == 0 and m.imposter_t_setup_ms == 0
    assert tom.tcr.read_cost_model(str(path)).t_tri_ms == pytest.approx(m.t_tri_ms)

    class Broken(GeometryRenderer):
        def time_frame(self, camera, draws, way):
            raise ValueError("the GPU is gone")
    with pytest.raises(ValueError, match="the GPU is gone"):
        tom.tcr.calibrate(Broken(), [f.meshes[0]])
    with pytest.raises(tom.ArgumentError, match="no meshes"):
        tom.tcr.calibrate(renderer, [])
