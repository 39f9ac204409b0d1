"""python3 -m tightex.tiles on small generated tile sets, with a 2-worker LocalCluster: a folder and a
tileset.json, one bad tile among them, a worker killed mid-run, a re-run that skips every tile."""
import json
import os
import signal
import struct
import subprocess
import sys
import time

import pytest

from conftest import batch_id_errors, glb_with_batch_ids, make_bad_obj, make_boxes, make_two_pages

pytest.importorskip("distributed")


def run_tiles(*args):
    """The tiles command as a new user runs it; its exit status and stderr."""
    p = subprocess.run([sys.executable, "-m", "tightex.tiles", *map(str, args)], capture_output=True, text=True, timeout=300)
    return p.returncode, p.stderr


def tile_folder(root, boxes=(30, 60, 45), small=0):
    """ROOT/a/t0, a/t1, b/t2 (boxes models, as many components as boxes; b/t2 on two texture pages),
    `small` more tiles c/s<i> of 2 to 9 boxes, and b/bad.obj."""
    for i, count in enumerate(boxes):
        (make_two_pages if i == 2 else make_boxes)(os.path.join(root, "a" if i < 2 else "b", f"t{i}"), count, i + 1)
    for i in range(small):
        make_boxes(os.path.join(root, "c", f"s{i}"), 2 + i % 8, 100 + i)
    make_bad_obj(os.path.join(root, "b", "bad.obj"))
    # Nothing to bake: no material, no texture: copied through.
    with open(os.path.join(root, "b", "plain.obj"), "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n")


def check_done_tile(record):
    """A tile done: its model and report there, nothing lost or flipped, the texture used."""
    assert record["status"] in ("done", "skipped") and record["error"] is None
    assert os.path.isfile(record["content"])
    with open(os.path.join(os.path.dirname(record["content"]), "report.json")) as f:
        m = json.load(f)["metrics"]
    assert m["lost_triangles"] == 0 and m["flipped"] == 0 and m["output"]["utilization"] >= 0.99
    assert record["input_texels"] > 0 and record["output_texels"] > 0 and record["psnr_db"] > 0


def no_temporaries(root):
    return [os.path.join(d, n) for d, dirs, files in os.walk(root) for n in dirs + files if ".tmp-" in n or ".old-" in n]


def test_folder_bad_tile_and_rerun(tightex, tmp_path):
    tile_folder(tmp_path / "in", small=12)  # 17 tiles
    rc, err = run_tiles(tmp_path / "in", tmp_path / "out", "--workers", "2", "--size", "128")
    assert rc == 1, err
    with open(tmp_path / "out" / "summary.json") as f:
        summary = json.load(f)
    assert (summary["done"], summary["passed_through"], summary["failed"], summary["workers"]) == (15, 1, 1, 2)
    records = {r["tile"]: r for r in summary["per_tile"]}
    for tile, record in records.items():
        if tile not in ("b/bad.obj", "b/plain.obj"):
            check_done_tile(record)
    plain = records["b/plain.obj"]
    assert plain["status"] == "passed_through" and "b/plain.obj: passed through: nothing to bake" in err
    with open(plain["content"]) as copied, open(tmp_path / "in" / "b" / "plain.obj") as original:
        assert copied.read() == original.read()
    with open(os.path.join(os.path.dirname(records["b/t2/boxes.obj"]["content"]), "report.json")) as f:
        assert len(json.load(f)["metrics"]["input"]["image_utilization"]) == 2  # both pages read
    bad = records["b/bad.obj"]
    assert bad["status"] == "failed" and bad["error"].startswith("InputError: ") and "bad.obj:" in bad["error"]
    assert "\n" not in bad["error"] and "b/bad.obj: InputError" in err
    with open(tmp_path / "out" / "summary.csv") as f:
        assert len(f.read().splitlines()) == 18
    assert not no_temporaries(tmp_path / "out")
    assert not [n for d, _, files in os.walk(tmp_path / "out") for n in files if n == "report.html"], "no page per tile without --html"

    # A re-run settles every tile from the manifest: nothing runs, no output is touched.
    mtimes = {t: os.stat(records[t]["content"]).st_mtime_ns for t in records if records[t]["status"] == "done"}
    rc, err = run_tiles(tmp_path / "in", tmp_path / "out", "--workers", "2", "--size", "128")
    assert rc == 1 and "0 to do" in err, err
    with open(tmp_path / "out" / "summary.json") as f:
        again = json.load(f)
    assert (again["skipped"], again["passed_through"], again["failed"], again["workers"]) == (15, 1, 1, 0)
    assert all(os.stat(records[t]["content"]).st_mtime_ns == m for t, m in mtimes.items())
    # Changed options redo the tiles.
    rc, err = run_tiles(tmp_path / "in", tmp_path / "out", "--workers", "2", "--size", "64")
    assert rc == 1 and "17 to do" in err, err


def write_tileset(root, tileset):
    with open(root / "tileset.json", "w") as f:
        json.dump(tileset, f)


def test_tileset_rewritten_to_new_content(tightex, tmp_path):
    from tightex.b3dm import B3dm, build_b3dm
    root = tmp_path / "in"
    for i, count in enumerate((20, 30, 25)):
        make_boxes(root / "tiles" / f"t{i}", count, i + 1)
    # A b3dm whose embedded model tightex cannot read: failed, copied unchanged.
    (root / "tiles" / "x.b3dm").write_bytes(build_b3dm(B3dm(b'{"BATCH_LENGTH":0}', b"", b"", b"", b"glTF" + bytes(16))))
    box = {"box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 10]}
    sub = {"asset": {"version": "1.0"}, "geometricError": 10,
           "root": {"boundingVolume": box, "geometricError": 0, "content": {"uri": "../tiles/t2/boxes.obj"}}}
    (root / "sub").mkdir()
    (root / "sub" / "tileset.json").write_text(json.dumps(sub))
    children = [{"boundingVolume": box, "geometricError": 0, "content": {"uri": f"tiles/t{i}/boxes.obj"}} for i in range(2)]
    children += [{"boundingVolume": box, "geometricError": 0, "content": {"uri": "tiles/x.b3dm"}},
                 {"boundingVolume": box, "geometricError": 5, "content": {"uri": "sub/tileset.json"}}]
    tileset = {"asset": {"version": "1.0"}, "geometricError": 100, "root": {"boundingVolume": box, "geometricError": 50,
                                                                         "refine": "ADD", "children": children}}
    write_tileset(root, tileset)
    out = tmp_path / "out"
    rc, err = run_tiles(root / "tileset.json", out, "--workers", "2")
    assert rc == 1, err
    with open(out / "summary.json") as f:
        summary = json.load(f)
    assert (summary["done"], summary["failed"]) == (3, 1)
    for path in (out / "tileset.json", out / "sub" / "tileset.json"):
        with open(path) as f:
            written = json.load(f)
        with open(root / os.path.relpath(path, out)) as f:
            original = json.load(f)
        uris = []
        for new, old in zip(walk(written["root"]), walk(original["root"])):
            assert new["boundingVolume"] == old["boundingVolume"]
            if "content" in old:
                uris.append(new["content"].pop("uri"))
                old["content"].pop("uri")
        assert written == original  # nothing but the URIs changed
        for uri in uris:
            assert os.path.isfile(os.path.join(os.path.dirname(path), uri)), uri
    assert (out / "tiles" / "x.b3dm").read_bytes() == (root / "tiles" / "x.b3dm").read_bytes()
    with open(out / "tileset.json") as f:
        assert json.load(f)["root"]["children"][0]["content"]["uri"] == "tiles/t0/boxes/boxes.obj"


def test_glb_and_b3dm_tileset(tightex, tmp_path):
    """A 3D Tiles set of 14 tiles: 1.0 b3dm (feature and batch tables, _BATCHID per vertex) and 1.1 GLB
    content, one corrupt GLB. Every good tile comes out optimized in its own kind, the b3dm tables byte
    for byte, every vertex still in its batch."""
    from tightex.b3dm import B3dm, build_b3dm, parse_b3dm
    root = tmp_path / "in"
    (root / "tiles").mkdir(parents=True)
    box = {"box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 10]}
    children, tables = [], {}
    for i in range(13):
        obj = make_boxes(tmp_path / "src" / f"t{i}", 3 + i % 9, 200 + i)
        tightex.optimize(obj, tmp_path / "glb" / f"t{i}", model_format="glb", size=64, html=False)
        glb = glb_with_batch_ids((tmp_path / "glb" / f"t{i}" / "boxes.glb").read_bytes(), 5)
        if i % 2 == 0:
            tables[f"t{i}.b3dm"] = (b'{"BATCH_LENGTH":5}', b"", b'{"name":["a","b","c","d","e"]}', b"")
            (root / "tiles" / f"t{i}.b3dm").write_bytes(build_b3dm(B3dm(*tables[f"t{i}.b3dm"], glb)))
        else:
            (root / "tiles" / f"t{i}.glb").write_bytes(glb)
        children.append({"boundingVolume": box, "geometricError": 0, "content": {"uri": f"tiles/t{i}.{'b3dm' if i % 2 == 0 else 'glb'}"}})
    (root / "tiles" / "bad.glb").write_bytes(b"glTF" + struct.pack("<II", 2, 4000) + bytes(40))
    children.append({"boundingVolume": box, "geometricError": 0, "content": {"uri": "tiles/bad.glb"}})
    write_tileset(root, {"asset": {"version": "1.1"}, "geometricError": 100,
                         "root": {"boundingVolume": box, "geometricError": 50, "refine": "ADD", "children": children}})
    out = tmp_path / "out"
    rc, err = run_tiles(root / "tileset.json", out, "--workers", "2")
    assert rc == 1, err
    with open(out / "summary.json") as f:
        summary = json.load(f)
    assert (summary["done"], summary["failed"]) == (13, 1), err
    for record in summary["per_tile"]:
        if record["tile"].endswith("bad.glb"):
            assert record["status"] == "failed" and "bad.glb" in record["error"] and "\n" not in record["error"]
            continue
        check_done_tile(record)
        content = record["content"]
        data = open(content, "rb").read()
        if content.endswith(".b3dm"):
            tile = parse_b3dm(data, content)
            original = tables[os.path.basename(record["tile"])]
            assert (tile.feature_table_json.rstrip(b" "), tile.feature_table_binary, tile.batch_table_json.rstrip(b" "),
                    tile.batch_table_binary) == original
            data = tile.glb
        else:
            assert content.endswith(".glb")
        wrong, checked = batch_id_errors(data, 5)
        assert checked > 0 and wrong == 0, (content, wrong, checked)
    with open(out / "tileset.json") as f:
        written = json.load(f)
    for child in written["root"]["children"]:
        assert os.path.isfile(out / child["content"]["uri"]), child
    assert not no_temporaries(out)


def walk(tile):
    yield tile
    for child in tile.get("children", []):
        yield from walk(child)


def test_killed_worker_tile_is_retried(tightex, tmp_path):
    from distributed import Client, LocalCluster
    for i in range(4):
        make_boxes(tmp_path / "in" / f"t{i}", 300, i + 1)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, resources={"memory": 2**34}, dashboard_address=None,
                      silence_logs=50) as cluster, Client(cluster) as client:
        command = [sys.executable, "-m", "tightex.tiles", tmp_path / "in", tmp_path / "out", "--scheduler", cluster.scheduler_address]
        proc = subprocess.Popen(list(map(str, command)), stderr=subprocess.PIPE, text=True)
        busy = {}
        deadline = time.monotonic() + 60
        while not busy and time.monotonic() < deadline and proc.poll() is None:
            busy = {w: keys for w, keys in client.processing().items() if keys}
            time.sleep(0.02)
        assert busy, "no tile ever ran"
        victim = next(iter(busy))
        pid = client.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        _, err = proc.communicate(timeout=240)
        assert victim not in client.scheduler_info()["workers"]
    assert proc.returncode == 0, err
    with open(tmp_path / "out" / "summary.json") as f:
        summary = json.load(f)
    assert summary["done"] == 4
    for record in summary["per_tile"]:
        check_done_tile(record)
    assert not no_temporaries(tmp_path / "out")


def test_memory_resource_keeps_big_tiles_apart(tightex, tmp_path):
    for i in range(4):
        make_boxes(tmp_path / "in" / f"t{i}", 40, i + 1)
    estimate = max(tightex.estimate_memory(tmp_path / "in" / f"t{i}" / "boxes.obj") for i in range(4))
    # One worker with two threads, offering 1.5 tiles' memory: never two tiles at once.
    rc, err = run_tiles(tmp_path / "in", tmp_path / "out", "--workers", "1", "--threads-per-worker", "2",
                        "--memory-per-worker", 1.5 * estimate / 2**20)
    assert rc == 0, err
    with open(tmp_path / "out" / "summary.json") as f:
        spans = sorted((r["started"], r["finished"]) for r in json.load(f)["per_tile"])
    assert len(spans) == 4
    assert all(later[0] >= earlier[1] for earlier, later in zip(spans, spans[1:]))


def test_bad_command_line_is_refused_before_any_work(tightex, tmp_path):
    tile_folder(tmp_path / "in", boxes=(10,))
    for args, message in ((["--size", "3"], "--size"), (["--report", "r.json"], "--report"), ([], "outside the input")):
        out = tmp_path / "in" / "out" if not args else tmp_path / "out"
        rc, err = run_tiles(tmp_path / "in", out, *args)
        assert rc == 2 and message in err, err
        assert not out.exists()


def test_folder_with_a_tileset_is_the_tileset_and_an_empty_folder_is_refused(tightex, tmp_path):
    root = tmp_path / "in"
    for i, count in enumerate((12, 16)):
        make_boxes(root / "tiles" / f"t{i}", count, i + 1)
    box = {"box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 10]}
    children = [{"boundingVolume": box, "geometricError": 0, "content": {"uri": f"tiles/t{i}/boxes.obj"}} for i in range(2)]
    write_tileset(root, {"asset": {"version": "1.0"}, "geometricError": 100,
                         "root": {"boundingVolume": box, "geometricError": 50, "refine": "ADD", "children": children}})
    out = tmp_path / "out"
    rc, err = run_tiles(root, out, "--workers", "1")
    assert rc == 0, err
    with open(out / "tileset.json") as f:
        written = json.load(f)
    assert [c["content"]["uri"] for c in written["root"]["children"]] == ["tiles/t0/boxes/boxes.obj", "tiles/t1/boxes/boxes.obj"]
    empty = tmp_path / "empty"
    (empty / "sub").mkdir(parents=True)
    (empty / "sub" / "notes.txt").write_text("no models here")
    rc, err = run_tiles(empty, tmp_path / "out2")
    assert rc == 2 and "no model file" in err, err
    assert not (tmp_path / "out2").exists()


def files_under(root):
    return sorted(os.path.relpath(os.path.join(d, n), root) for d, _, files in os.walk(root) for n in files)


def test_hostile_tileset_contents_are_listed_and_nothing_leaves_the_folders(tightex, tmp_path):
    """Contents that lead out of the tileset's folder (.., absolute, file:, a symbolic link, a nested
    tileset that escapes or lies outside), remote ones and one of a kind the runner does not read: each
    listed in the summary with its reason, counted, exit 1 (0 with --skip-unreadable); nothing outside
    INPUT read into OUTPUT, nothing written outside OUTPUT. With --allow-outside-files the outside ones
    run, written under OUTPUT/_outside."""
    vendor = tmp_path / "vendor"
    root = vendor / "in"
    make_boxes(root / "tiles" / "t0", 6, 1)
    make_boxes(vendor / "evil", 4, 2)
    os.symlink(vendor / "evil", root / "tiles" / "link")
    (root / "tiles" / "p.pnts").write_bytes(b"pnts")
    box = {"box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 10]}

    def tileset(uris):
        children = [{"boundingVolume": box, "geometricError": 0, "content": {"uri": u}} for u in uris]
        return {"asset": {"version": "1.1"}, "geometricError": 100,
                "root": {"boundingVolume": box, "geometricError": 50, "refine": "ADD", "children": children}}

    (root / "sub").mkdir()
    (root / "sub" / "tileset.json").write_text(json.dumps(tileset(["../../evil/boxes.obj"])))
    (vendor / "outer").mkdir()
    (vendor / "outer" / "tileset.json").write_text(json.dumps(tileset(["../evil/boxes.obj"])))
    outside = ["../evil/boxes.obj", str(vendor / "evil" / "boxes.obj"), "file://" + str(vendor / "evil" / "boxes.obj"),
               "tiles/link/boxes.obj", "../outer/tileset.json"]
    remote = ["http://example.com/t.glb", "https://example.com/t.b3dm"]
    write_tileset(root, tileset(["tiles/t0/boxes.obj", "sub/tileset.json", "tiles/p.pnts"] + outside + remote))
    before = files_under(vendor)
    out = vendor / "out" / "a" / "b"
    rc, err = run_tiles(root / "tileset.json", out, "--workers", "1", "--size", "64")
    assert rc == 1, err
    with open(out / "summary.json") as f:
        summary = json.load(f)
    assert (summary["done"], summary["refused"], summary["remote"], summary["unreadable"], summary["failed"]) == (1, 6, 2, 1, 0), summary
    assert "1 done" in err and "6 refused, 2 remote, 1 unreadable" in err, err
    records = {r["tile"]: r for r in summary["per_tile"]}
    for uri in outside:
        r = records[f"tileset.json: {uri}"]
        assert r["status"] == "refused" and uri in r["error"] and "--allow-outside-files" in r["error"], r
    assert records["sub/tileset.json: ../../evil/boxes.obj"]["status"] == "refused"
    assert "symbolic link" in records["tileset.json: tiles/link/boxes.obj"]["error"]
    for uri in remote:
        assert records[f"tileset.json: {uri}"]["status"] == "remote"
    assert ".pnts" in records["tileset.json: tiles/p.pnts"]["error"]
    assert (out / "tiles" / "p.pnts").read_bytes() == b"pnts"  # copied through: the tileset stays complete
    with open(out / "summary.csv") as f:
        assert len(f.read().splitlines()) == 1 + len(records)
    # Nothing written outside OUTPUT, nothing of the model outside INPUT in it.
    assert [p for p in files_under(vendor) if p not in before and not p.startswith(os.path.join("out", "a", "b") + os.sep)] == []
    assert os.listdir(vendor / "out" / "a") == ["b"]
    assert not [p for p in files_under(out) if "evil" in p or p.startswith("_outside")]

    rc, err = run_tiles(root / "tileset.json", out, "--workers", "1", "--size", "64", "--skip-unreadable")
    assert rc == 0, err

    allowed = vendor / "allowed"
    rc, err = run_tiles(root / "tileset.json", allowed, "--workers", "1", "--size", "64", "--allow-outside-files", "--skip-unreadable")
    assert rc == 0, err
    with open(allowed / "summary.json") as f:
        summary = json.load(f)
    assert (summary["done"], summary["refused"], summary["remote"], summary["unreadable"]) == (3, 0, 2, 1), summary
    assert [p for p in files_under(vendor) if p not in before and not p.startswith(("out" + os.sep, "allowed" + os.sep))] == []
    evil_out = [r["content"] for r in summary["per_tile"] if r["tile"].startswith("_outside/")]
    assert evil_out and all(c.startswith(str(allowed / "_outside") + os.sep) for c in evil_out), evil_out
    with open(allowed / "tileset.json") as f:
        for child in json.load(f)["root"]["children"]:
            uri = child["content"]["uri"]
            assert uri.startswith("http") or os.path.exists(allowed / uri), uri


def test_redo_is_the_tile_runners_word_and_force_its_deprecated_alias(tightex, capsys):
    from tightex.tiles import parse_command_line
    opts, fields = parse_command_line(["in", "out", "--redo", "--size", "256"])
    assert opts.redo and fields["size"] == 256
    assert "--force" not in capsys.readouterr().err
    opts, fields = parse_command_line(["in", "out", "--force"])
    assert opts.redo and fields["allow_large_textures"] is False
    assert "--force is deprecated here: it is --redo" in capsys.readouterr().err
    # The tightex command's --force (large textures) is --allow-large-size here.
    opts, fields = parse_command_line(["in", "out", "--allow-large-size"])
    assert not opts.redo and fields["allow_large_textures"] is True
