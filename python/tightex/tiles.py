"""Whole tile sets through tightex on a Dask cluster: one task per tile.

    /usr/bin/python3 -m tightex.tiles INPUT OUTPUT [--scheduler ADDRESS] [--workers N] [--redo] [tightex options]

INPUT is a folder of models (.obj, .ply, and .glb where the library reads it; searched recursively),
or a 3D Tiles ``tileset.json`` whose content is 1.0 ``.b3dm`` (the embedded GLB is optimized; the
feature and batch tables are kept byte for byte), 1.1 ``.glb`` or a model file (external tilesets,
``.json`` content, are followed); a folder with a ``tileset.json`` at its top is that tileset. A folder
with neither is refused (exit status 2). OUTPUT mirrors INPUT: the tile ``a/b/t.obj`` is written to the folder
``OUTPUT/a/b/t/`` (its model, material, texture and ``report.json``), and each tileset.json is rewritten
with its content URIs pointing at the new files (bounding volumes and everything else unchanged).

tightex options (``--size 1024``, ``--map area``, ...) come after INPUT and OUTPUT and are the
command's; ``--allow-large-size`` passes the command's own ``--force``.

- Without ``--scheduler`` a LocalCluster runs on this machine (``--workers`` processes, default one per
  core); with it, the running cluster at that address.
- Each task asks for the memory tightex's own guard estimates (``tightex.estimate_memory``) as the
  worker resource "memory"; local workers offer their share of this machine's memory, so a worker never
  runs two tiles together that would not fit. Workers of an external cluster that declare no "memory"
  resource run tiles without that check (a note says so).
- A tile with nothing to bake (no texture, no vertex colours: the command refuses it) is copied through
  unchanged and listed as "passed_through", not as failed.
- A tile whose input is bad is reported with its one-line error and the others complete; a tile whose
  worker died is retried elsewhere (Dask's allowed-failures). A tile's outputs are written into a
  temporary folder beside it and renamed into place, so a half tile never appears.
- ``OUTPUT/manifest.jsonl`` records each tile done (or refused as bad input), with the hash of its
  input files and the options; a re-run skips those whose hash, options and output still match (a
  refused tile is reported failed again without a run), unless ``--redo`` (``--force``, its former name,
  still works and warns: the command's ``--force`` is another thing). Tiles that failed
  otherwise (a worker died too often, a full disk) are run again. A failed tile of
  a tileset gets its input content copied unchanged, so the tileset stays complete.
- Untrusted input stays inside its folder (docs/architecture.md, "Files a model names"): a content URI
  must name a file inside INPUT's folder (the top tileset's) once ``..`` is resolved and symbolic links
  followed; an absolute path, a ``file:`` URI or one that leads out is refused, unless
  ``--allow-outside-files`` (which the models' own references obey too); such a content allowed is
  written under ``OUTPUT/_outside/``: nothing is ever written outside OUTPUT.
- Nothing is skipped in silence: a remote (http, https) content, one the runner cannot read (another
  format, an unreadable external tileset) and one refused by the rule above are listed in the summary
  ("remote", "unreadable", "refused", with the reason) and counted in the closing line; a local content
  of another kind is copied through unchanged, so that the tileset stays complete.
- At the end ``OUTPUT/summary.json`` and ``summary.csv``: per tile its status, input and output texels,
  surface PSNR, time, peak memory (the worker process's peak resident set during the tile) and error.

Exit status: 0 when every tile is done or skipped, 1 when some failed, or some content was remote,
unreadable or refused without ``--skip-unreadable`` (see the summary), 2 for a bad command line.
"""

import argparse
import csv
import hashlib
import importlib.util
import json
import logging
import os
import re
import shutil
import sys
import time
import urllib.parse
import uuid
from concurrent.futures import ThreadPoolExecutor

MODEL_EXTENSIONS = (".obj", ".ply", ".glb")
CONTENT_EXTENSIONS = MODEL_EXTENSIONS + (".b3dm",)
MANIFEST = "manifest.jsonl"
#: The statuses of contents that were not run: each listed in the summary with its reason.
NOT_RUN = ("refused", "remote", "unreadable")
#: Where a content outside INPUT's folder (only with --allow-outside-files) is written, under OUTPUT.
OUTSIDE = "_outside"
CSV_COLUMNS = ("tile", "status", "input_texels", "input_used_texels", "output_texels", "psnr_db", "lost_triangles", "flipped",
               "seconds", "peak_mib", "error")


# ----------------------------------------------------------------------------------------------
# One tile, on a worker.


def _reset_peak_memory():
    """Starts a new peak of this process's resident set (Linux: /proc/self/clear_refs 5)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def _peak_memory_mib():
    """This process's peak resident set since the last reset, in MiB (VmHWM); None where unknown."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def _replace_folder(tmp, final):
    """Renames the folder ``tmp`` to ``final``; a previous ``final`` is moved aside first and removed
    after, so ``final`` is always either the old tile or the new one, whole."""
    old = None
    if os.path.exists(final):
        old = f"{final}.old-{uuid.uuid4().hex[:8]}"
        os.rename(final, old)
    os.rename(tmp, final)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def _optimize_model(model, outdir, options):
    """The library's run on one model file with the option fields ``options`` (a dict); returns the
    report (a dict) and the output model's file name."""
    from . import Options, optimize
    report = optimize(model, outdir, Options(**options)).to_dict()
    return report, report["output"]["model"]


def _optimize_b3dm(path, outdir, options):
    """A .b3dm tile: its GLB optimized and wrapped again with the input's tables. Returns the report
    and the output file's name."""
    from . import _tightex
    from .b3dm import B3dm, build_b3dm, parse_b3dm
    with open(path, "rb") as f:
        tile = parse_b3dm(f.read(), path)
    stem = os.path.splitext(os.path.basename(path))[0]
    work = os.path.join(outdir, ".input")
    os.makedirs(work)
    glb_in = os.path.join(work, stem + ".glb")
    with open(glb_in, "wb") as f:
        f.write(tile.glb)
    report, model = _optimize_model(glb_in, outdir, options)
    shutil.rmtree(work)
    if not model.lower().endswith(".glb"):
        raise _tightex.InputError(f"{path}: tightex wrote {model}, not a GLB, so it cannot go back into the b3dm")
    glb_out = os.path.join(outdir, model)
    with open(glb_out, "rb") as f:
        tile.glb = f.read()
    os.remove(glb_out)
    with open(os.path.join(outdir, stem + ".b3dm"), "wb") as f:
        f.write(build_b3dm(tile))
    report["output"]["model"] = stem + ".b3dm"
    with open(os.path.join(outdir, "report.json"), "w") as f:
        json.dump(report, f, indent=2)
    return report, stem + ".b3dm"


# The library's message for a model with nothing to bake ("FILE: nothing to bake: ..."): such a tile is
# copied through as it is.
NOTHING_TO_BAKE = ": nothing to bake: "


def _pass_through(tile, outdir):
    """Copies the tile's input (a model with the files it names, or a b3dm) into ``outdir`` unchanged;
    returns the copied content's file name."""
    files = [tile["input"]] + (_referenced_files(tile["input"]) if tile["kind"] == "model" else [])
    base = os.path.dirname(tile["input"])
    for f in files:
        target = os.path.join(outdir, os.path.relpath(f, base))
        if not inside(target, outdir):
            continue  # a file named outside the model's folder (--allow-outside-files): never written outside outdir
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(f, target)
    return os.path.basename(tile["input"])


def _figures(report):
    """The summary's figures from a tile's report."""
    m = report.get("metrics", {})
    return {
        "input_texels": m.get("input", {}).get("texels"),
        "input_used_texels": m.get("input", {}).get("used_texels"),
        "output_texels": m.get("output", {}).get("texels"),
        "psnr_db": m.get("surface_psnr_db"),
        "lost_triangles": m.get("lost_triangles"),
        "flipped": m.get("flipped"),
    }


def run_tile(tile, options):
    """Optimizes one tile (a dict: "id", "input", "out_dir", "kind" "model" or "b3dm", "threads" for
    tightex's parallel work, None: all cores) with the option fields ``options`` (a dict of
    tightex.Options fields), into a temporary folder renamed to tile["out_dir"] when complete.
    Returns its summary record; a tightex error or a file system error is the record's "error" (one
    line), anything else (a bug) is raised. Removes what an earlier attempt at the tile left (its
    worker killed mid-tile) first."""
    from . import Error, _tightex
    start = time.monotonic()
    if tile.get("threads"):
        _tightex.set_max_threads(tile["threads"])
    _reset_peak_memory()
    final = tile["out_dir"]
    if not inside(final, tile["output_root"]):
        raise RuntimeError(f"{tile['id']}: output folder {final} is not under {tile['output_root']}")
    parent = os.path.dirname(final)
    os.makedirs(parent, exist_ok=True)
    prefix = f".{os.path.basename(final)}.tmp-"
    for left in os.listdir(parent):  # an earlier attempt's, whose worker died mid-tile
        if left.startswith(prefix):
            shutil.rmtree(os.path.join(parent, left), ignore_errors=True)
    tmp = os.path.join(parent, prefix + uuid.uuid4().hex[:8])
    record = {"tile": tile["id"], "status": "failed", "error": None}
    try:
        os.makedirs(tmp)
        run = _optimize_b3dm if tile["kind"] == "b3dm" else _optimize_model
        report, content = run(tile["input"], tmp, options)
        _replace_folder(tmp, final)
        record.update(_figures(report), status="done", content=os.path.join(final, content))
    except (Error, OSError) as e:
        record["error"] = f"{type(e).__name__}: {e}".replace("\n", " ")
        if isinstance(e, Error) and NOTHING_TO_BAKE in str(e):
            content = _pass_through(tile, tmp)
            _replace_folder(tmp, final)
            record.update(status="passed_through", error=None, content=os.path.join(final, content), note="passed through: nothing to bake")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    record["seconds"] = time.monotonic() - start
    record["finished"] = time.time()
    record["started"] = record["finished"] - record["seconds"]
    record["peak_mib"] = _peak_memory_mib()
    return record


# ----------------------------------------------------------------------------------------------
# Finding the tiles.


def inside(path, folder):
    """Whether ``path`` lies in ``folder`` (or is it), symbolic links followed (a path that does not
    exist yet: as far as it does)."""
    real, root = os.path.realpath(path), os.path.realpath(folder)
    return real == root or real.startswith(root.rstrip(os.sep) + os.sep)


def _referenced_files(path, allow_outside=False):
    """The files a model names (an OBJ's MTL libraries and their textures, a PLY's TextureFile
    comments), found as written relative to the model's folder; those missing are left out (the run
    reports them), and those outside the model's folder unless ``allow_outside`` (the library refuses
    them), so that hashing or copying a model never opens a file outside its folder."""
    folder = os.path.dirname(path)
    found = []
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext == ".obj":
            with open(path, "rb") as f:
                for line in f:
                    if line.startswith(b"mtllib"):
                        found += [os.path.join(folder, n.decode("utf-8", "replace")) for n in line.split()[1:]]
            for mtl in list(found):
                if (allow_outside or inside(mtl, folder)) and os.path.isfile(mtl):
                    with open(mtl, "rb") as f:
                        for line in f:
                            words = line.split()
                            if words and words[0].lower().startswith(b"map_") and len(words) > 1:
                                found.append(os.path.join(os.path.dirname(mtl), words[-1].decode("utf-8", "replace")))
        elif ext == ".ply":
            with open(path, "rb") as f:
                for line in f:
                    if line.startswith(b"comment TextureFile"):
                        found.append(os.path.join(folder, line.split(None, 2)[2].strip().decode("utf-8", "replace")))
                    if line.startswith(b"end_header"):
                        break
    except OSError:
        pass
    return [p for p in found if (allow_outside or inside(p, folder)) and os.path.isfile(p)]


def input_hash(path, allow_outside=False):
    """SHA-256 over a tile's model file and the files it names (names and contents); "missing" for a
    model file that is not there (its run reports it)."""
    if not os.path.isfile(path):
        return "missing"
    h = hashlib.sha256()
    for p in [path] + sorted(set(_referenced_files(path, allow_outside))):
        h.update(os.path.basename(p).encode() + b"\0")
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


def _relative_output(path, input_root):
    """Where the input file ``path`` goes, relative to OUTPUT: its path under ``input_root``; a file
    outside it (--allow-outside-files) under _outside/ with its absolute path, so never outside OUTPUT."""
    rel = os.path.relpath(os.path.abspath(path), input_root)
    if rel == os.pardir or rel.startswith(os.pardir + os.sep):
        rel = os.path.join(OUTSIDE, os.path.abspath(path).lstrip(os.sep))
    return rel


def _tile(input_root, output_root, path):
    """The task description of the model or content file ``path`` under ``input_root``."""
    rel = _relative_output(path, input_root)
    stem, ext = os.path.splitext(rel)
    return {"id": rel.replace(os.sep, "/"), "input": os.path.abspath(path), "out_dir": os.path.join(output_root, stem),
            "output_root": output_root, "kind": "b3dm" if ext.lower() == ".b3dm" else "model"}


def folder_tiles(input_root, output_root, allow_outside=False):
    """Every model file under ``input_root`` (sorted), as tasks writing under ``output_root``, and the
    records of those refused (a symbolic link out of the folder, without ``allow_outside``). Two models
    of the same stem in one folder (a.obj, a.ply) get folders named with their extension. Symbolic
    links to folders are not followed."""
    paths, refused = [], []
    for folder, dirs, files in os.walk(input_root):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for f in sorted(files):
            path = os.path.join(folder, f)
            if os.path.splitext(f)[1].lower() not in MODEL_EXTENSIONS:
                continue
            if allow_outside or inside(path, input_root):
                paths.append(path)
            else:
                rel = os.path.relpath(path, input_root).replace(os.sep, "/")
                refused.append(_not_run(rel, "refused", f"{rel} {_LINK_OUT}{_LIFT}"))
    tiles = [_tile(input_root, output_root, p) for p in paths]
    stems = [t["out_dir"] for t in tiles]
    for t in tiles:
        if stems.count(t["out_dir"]) > 1:
            t["out_dir"] = os.path.join(output_root, _relative_output(t["input"], input_root))
    return tiles, refused


def _contents(tile_json):
    """The content objects of one tile of a tileset (1.0 "content", 1.1 "contents")."""
    found = [tile_json["content"]] if isinstance(tile_json.get("content"), dict) else []
    return found + [c for c in tile_json.get("contents", []) if isinstance(c, dict)]


def _walk_tiles(tile_json):
    """Every tile of a tileset's tree, depth first."""
    stack = [tile_json]
    while stack:
        t = stack.pop()
        yield t
        stack += reversed(t.get("children", []))


_LIFT = " (--allow-outside-files reads it)"
_LINK_OUT = "is a symbolic link that leads out of the input folder"


def _not_run(tile_id, status, reason):
    """The summary record of a content that was not run (NOT_RUN), with its reason."""
    return {"tile": tile_id, "status": status, "error": reason}


def content_target(uri, base, input_root, allow_outside=False):
    """The file a content URI names, relative to the folder ``base`` of the tileset naming it, as
    (path, None); or (None, (status, reason)) for a content not run: "remote" (http, https),
    "refused" (absolute, file:, leading out of ``input_root`` or a symbolic link out, unless
    ``allow_outside``) or "unreadable" (another URI scheme)."""
    parsed = urllib.parse.urlparse(uri)
    scheme = parsed.scheme.lower()
    if len(scheme) == 1:  # a Windows drive, "C:/tiles/t.glb": an absolute path
        scheme, path = "", uri
    else:
        path = urllib.parse.unquote(parsed.path)
    if scheme in ("http", "https") or (not scheme and parsed.netloc):
        return None, ("remote", "is remote (http, https): not fetched, the tile runner reads local files")
    if scheme == "file":
        if not allow_outside:
            return None, ("refused", f"is a file: URI, which may name any file on this machine{_LIFT}")
        return os.path.normpath(path), None
    if scheme:
        return None, ("unreadable", f"is a {scheme}: URI, which the tile runner does not read")
    absolute = os.path.isabs(path) or re.match(r"[A-Za-z]:[/\\]", path) is not None
    target = os.path.normpath(os.path.join(base, path))
    if allow_outside:
        return target, None
    if absolute:
        return None, ("refused", f"is an absolute path{_LIFT}")
    rel = os.path.relpath(target, input_root)
    if rel == os.pardir or rel.startswith(os.pardir + os.sep):
        return None, ("refused", f"leads ('..') out of the input folder {input_root}{_LIFT}")
    if not inside(target, input_root):
        return None, ("refused", f"{_LINK_OUT}{_LIFT}")
    return target, None


def read_tileset(tileset_path, output_root, allow_outside=False):
    """The tilesets (this one and every external one its content names) and the tiles they hold.
    Returns (tilesets, tiles, not_run): each tileset a dict with "input", "output" (paths) and "json"
    (parsed), "refs" [(content dict, key, tile id, input path)], "nested" [(content dict, key, tileset
    path)], "copies" [(content dict, key, input path, output path)] of contents copied unchanged; tiles as folder_tiles gives them;
    not_run the records of contents not run (content_target's, an external tileset that cannot be
    read, a content of a kind the runner does not read), each named "TILESET: URI"."""
    from . import InputError
    input_root = os.path.dirname(os.path.abspath(tileset_path))
    tilesets, tiles, seen, not_run = [], {}, set(), {}
    queue = [(os.path.abspath(tileset_path), None)]
    while queue:
        path, named_by = queue.pop(0)
        if path in seen:
            continue
        seen.add(path)
        try:
            with open(path, "rb") as f:
                data = json.loads(f.read())
            if not isinstance(data, dict) or not isinstance(data.get("root"), dict):
                raise ValueError("no \"root\" tile")
        except (OSError, ValueError) as e:
            if named_by is None:
                raise InputError(f"{path}: not a readable tileset JSON ({e})")
            not_run[named_by] = _not_run(named_by, "unreadable", f"is not a readable tileset JSON ({e})".replace("\n", " "))
            continue
        rel_path = os.path.relpath(path, input_root).replace(os.sep, "/")
        entry = {"input": path, "output": os.path.join(output_root, _relative_output(path, input_root)), "json": data, "refs": [], "nested": [], "copies": []}
        for t in _walk_tiles(data["root"]):
            for content in _contents(t):
                key = "uri" if "uri" in content else "url"
                uri = str(content.get(key, ""))
                name = f"{rel_path}: {uri}"
                target, skipped = content_target(uri, os.path.dirname(path), input_root, allow_outside)
                ext = os.path.splitext(target)[1].lower() if target else ""
                if skipped is None and ext not in CONTENT_EXTENSIONS + (".json",):
                    skipped = ("unreadable", f"is a {ext or 'extensionless'} content, which the tile runner does not read "
                                             f"(it reads {', '.join(CONTENT_EXTENSIONS)} and tileset .json)")
                if skipped:
                    not_run[name] = _not_run(name, skipped[0], f"{name}: content {skipped[1]}")
                    if target:  # a local file of another kind: copied through, so that the tileset stays complete
                        entry["copies"].append((content, key, target, os.path.join(output_root, _relative_output(target, input_root))))
                elif ext == ".json":
                    queue.append((target, name))
                    entry["nested"].append((content, key, target))
                else:
                    tile = _tile(input_root, output_root, target)
                    tiles.setdefault(tile["id"], tile)
                    entry["refs"].append((content, key, tile["id"], target))
        tilesets.append(entry)
    for record in not_run.values():
        if not record["error"].startswith(record["tile"]):
            record["error"] = f"{record['tile']}: {record['error']}"
    return tilesets, list(tiles.values()), list(not_run.values())


def write_tilesets(tilesets, records, output_root):
    """Writes each tileset under OUTPUT with its content URIs pointing at the new files; a tile that
    failed keeps its URI, its input content copied there unchanged."""
    written = {ts["input"]: ts["output"] for ts in tilesets}
    for ts in tilesets:
        base = os.path.dirname(ts["output"])
        for content, key, target in ts["nested"]:  # an external tileset from outside INPUT: its place under OUTPUT
            if target in written and os.path.relpath(written[target], output_root).startswith(OUTSIDE + os.sep):
                content[key] = urllib.parse.quote(os.path.relpath(written[target], base).replace(os.sep, "/"))
        for content, key, tile_id, source in ts["refs"]:
            record = records.get(tile_id, {})
            if record.get("status") in ("done", "skipped", "passed_through") and record.get("content"):
                content[key] = urllib.parse.quote(os.path.relpath(record["content"], base).replace(os.sep, "/"))
            else:
                copy = os.path.join(output_root, tile_id)
                if not inside(copy, output_root):
                    raise RuntimeError(f"{tile_id}: {copy} is not under {output_root}")
                os.makedirs(os.path.dirname(copy), exist_ok=True)
                if os.path.isfile(source) and not os.path.exists(copy):
                    shutil.copyfile(source, copy)
                if tile_id.startswith(OUTSIDE + "/"):
                    content[key] = urllib.parse.quote(os.path.relpath(copy, base).replace(os.sep, "/"))
        for content, key, source, copy in ts["copies"]:
            if not inside(copy, output_root):
                raise RuntimeError(f"{source}: {copy} is not under {output_root}")
            if os.path.isfile(source):
                os.makedirs(os.path.dirname(copy), exist_ok=True)
                shutil.copyfile(source, copy)
                content[key] = urllib.parse.quote(os.path.relpath(copy, base).replace(os.sep, "/"))
        if not inside(ts["output"], output_root):
            raise RuntimeError(f"{ts['input']}: {ts['output']} is not under {output_root}")
        _write_atomically(ts["output"], json.dumps(ts["json"], indent=2) + "\n")


def _write_atomically(path, text):
    """Writes ``text`` to ``path`` through a temporary file renamed into place."""
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    tmp = f"{path}.tmp-{uuid.uuid4().hex[:8]}"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


# ----------------------------------------------------------------------------------------------
# Resuming.


def read_manifest(output_root):
    """The last record of each tile done in earlier runs: {tile id: {"hash", "options", "record"}}."""
    done = {}
    try:
        with open(os.path.join(output_root, MANIFEST)) as f:
            for line in f:
                try:
                    entry = json.loads(line)
                    done[entry["tile"]] = entry
                except (ValueError, KeyError):
                    continue  # a line cut short by a killed run
    except OSError:
        pass
    return done


def append_manifest(output_root, record, digest, options):
    """Records one tile done or refused as bad input (one JSON line, flushed at once, so a killed run loses no finished tile)."""
    with open(os.path.join(output_root, MANIFEST), "a") as f:
        f.write(json.dumps({"tile": record["tile"], "hash": digest, "options": options, "record": record}) + "\n")
        f.flush()
        os.fsync(f.fileno())


def is_done(tile, manifest, digest, options):
    """Whether an earlier run settled this tile from the same input and options: done with its output
    still there, or refused as bad input (InputError: the same input fails the same way)."""
    entry = manifest.get(tile["id"])
    if not entry or entry["hash"] != digest or entry.get("options") != options:
        return False
    record = entry["record"]
    if record.get("status") == "failed":
        return str(record.get("error", "")).startswith("InputError")
    return os.path.isfile(record.get("content") or "")


# ----------------------------------------------------------------------------------------------
# The run.


def _total_memory():
    """This machine's memory in bytes."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def _start_client(opts):
    """The Dask client: the cluster at --scheduler, or a LocalCluster of --workers processes, each
    offering its share of this machine's memory (or --memory-per-worker) as the resource "memory".
    Returns (client, cluster)."""
    from distributed import Client, LocalCluster
    if opts.scheduler:
        return Client(opts.scheduler), None
    workers = opts.workers or os.cpu_count() or 1
    threads = opts.threads_per_worker or max(1, (os.cpu_count() or 1) // workers)
    share = _total_memory() // workers
    offered = int(opts.memory_per_worker * 2**20) if opts.memory_per_worker else share
    dashboard = ":8787" if _has_bokeh() else None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True, memory_limit=share,
                           resources={"memory": offered}, dashboard_address=dashboard, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _has_bokeh():
    """Whether this process can serve Dask's dashboard (it needs bokeh); run on the scheduler."""
    return importlib.util.find_spec("bokeh") is not None


def _memory_offered(client):
    """The largest "memory" resource a worker of the cluster declares; 0 when none does."""
    workers = client.scheduler_info().get("workers", {}).values()
    return max((w.get("resources", {}).get("memory", 0) for w in workers), default=0)


def _estimate(tile, options):
    """Bytes tightex's guard estimates for the tile; for a b3dm (whose GLB is read on the worker) or a
    model the estimate cannot read, 16 times its file size."""
    from . import Error, Options, estimate_memory
    if tile["kind"] == "model":
        try:
            return estimate_memory(tile["input"], Options(**options))
        except Error:
            pass
    return 16.0 * os.path.getsize(tile["input"]) if os.path.isfile(tile["input"]) else 0.0


def _prepare(tile, manifest, options):
    """Hashes the tile's input; returns its record if an earlier run settled it (is_done), else None
    with tile["estimate"] set."""
    tile["hash"] = input_hash(tile["input"], options.get("allow_outside_files", False))
    if is_done(tile, manifest, tile["hash"], options):
        earlier = manifest[tile["id"]]["record"]
        status = {"done": "skipped", "passed_through": "passed_through"}.get(earlier["status"], "failed")
        return dict(earlier, status=status, skipped=True)
    tile["estimate"] = _estimate(tile, options)
    return None


def _duration(seconds):
    """``seconds`` as 1h02m, 3m05s or 12s."""
    s = int(seconds)
    return f"{s // 3600}h{s % 3600 // 60:02d}m" if s >= 3600 else f"{s // 60}m{s % 60:02d}s" if s >= 60 else f"{s}s"


class ProgressLine:
    """Tiles done / failed / running / queued and the ETA, on one line of stderr (rewritten on a
    terminal, else printed every 10 s)."""

    def __init__(self, total, skipped):
        self.total, self.skipped = total, skipped
        self.start = time.monotonic()
        self.last = 0.0
        self.tty = sys.stderr.isatty()

    def show(self, done, failed, running, final=False):
        now = time.monotonic()
        if not final and now - self.last < (0.5 if self.tty else 10.0):
            return
        self.last = now
        finished = done + failed
        queued = self.total - finished - running
        eta = (now - self.start) / finished * (self.total - finished) if finished else None
        line = (f"tiles: {done} done, {failed} failed, {running} running, {queued} queued of {self.total}"
                f"{f', {self.skipped} skipped' if self.skipped else ''}, "
                f"{'ETA ' + _duration(eta) if eta is not None and not final else _duration(now - self.start)}")
        if self.tty:
            sys.stderr.write("\r\033[K" + line + ("\n" if final else ""))
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _error_record(tile, exc):
    """The record of a tile whose task itself failed (its worker died too often, or a bug)."""
    return {"tile": tile["id"], "status": "failed", "error": f"{type(exc).__name__}: {exc}".replace("\n", " ")}


def run_tiles(client, tiles, options, output_root, use_resources, skipped=0):
    """Submits one task per tile and waits for them, printing progress and recording each tile done
    in the manifest. Returns {tile id: record}."""
    from distributed import wait
    futures = {}
    for tile in tiles:
        resources = {"memory": min(tile["estimate"], use_resources)} if use_resources else None
        futures[client.submit(run_tile, tile, options, key=f"tile-{uuid.uuid4().hex}", resources=resources, pure=False)] = tile
    records, pending = {}, set(futures)
    progress = ProgressLine(len(tiles), skipped)
    done = failed = 0
    while pending:
        try:
            wait(pending, timeout=0.5, return_when="FIRST_COMPLETED")
        except Exception:  # the timeout: nothing finished in the last half second
            pass
        finished = {f for f in pending if f.done()}
        pending -= finished
        for future in finished:
            tile = futures[future]
            try:
                record = future.result()
            except Exception as e:
                record = _error_record(tile, e)
            records[tile["id"]] = record
            if record["status"] in ("done", "passed_through") or str(record.get("error")).startswith("InputError"):
                append_manifest(output_root, record, tile["hash"], options)
            done += record["status"] in ("done", "passed_through")
            failed += record["status"] not in ("done", "passed_through")
        running = sum(len(v) for v in client.processing().values()) if pending else 0
        progress.show(done, failed, min(running, len(pending)))
    progress.show(done, failed, 0, final=True)
    return records


def write_summary(output_root, records, wall_seconds, workers):
    """OUTPUT/summary.json (totals and every tile's record) and summary.csv (one row per tile)."""
    rows = sorted(records.values(), key=lambda r: r["tile"])
    counts = {s: sum(r["status"] == s for r in rows) for s in ("done", "skipped", "passed_through", "failed") + NOT_RUN}
    summary = {"tiles": len(rows), **counts, "wall_seconds": wall_seconds, "workers": workers, "per_tile": rows}
    _write_atomically(os.path.join(output_root, "summary.json"), json.dumps(summary, indent=2) + "\n")
    tmp = os.path.join(output_root, f".summary.csv.tmp-{uuid.uuid4().hex[:8]}")
    with open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    os.replace(tmp, os.path.join(output_root, "summary.csv"))
    return summary


#: The Options fields the tiles command sets itself (where each tile's files go; --html, --allow-large-size).
_OWN_FIELDS = {"report_path", "preview_path", "html", "allow_large_textures"}
#: The type of a flag whose field has no value by default.
_FLAG_TYPES = {"png_level": int, "jpeg_quality": int, "webp_quality": int, "model_format": str, "texture_format": str}


def _aspect(value):
    """--aspect's value: "auto" (the library's kAspectAuto, -1: chosen per model even with --size) or a
    number."""
    return -1.0 if value == "auto" else float(value)


def _add_tightex_flags(ap):
    """The tightex command's flags for the Options fields (the library's table of them), each its own
    field's dest; a flag not given keeps the field's default."""
    from . import _tightex
    group = ap.add_argument_group("tightex options", "as the tightex command takes them (tightex --help)")
    defaults = _tightex.Options()
    for field, flag, text in _tightex.option_flags():
        if not flag or field in _OWN_FIELDS:
            continue
        default = getattr(defaults, field)
        if isinstance(default, bool):
            action = "store_false" if flag.startswith("--no-") else "store_true"
            group.add_argument(flag, dest=field, action=action, default=default, help=text.replace("%", "%%"))
        else:
            kind = _aspect if field == "aspect" else _FLAG_TYPES.get(field, type(default))
            group.add_argument(flag, dest=field, type=kind, default=None, help=text.replace("%", "%%"))


def _tightex_options(ap, opts):
    """The Options fields the command line gives (a dict), checked by the library."""
    from . import Error, FIELDS, Options, _tightex
    fields = {f: getattr(opts, f) for f in FIELDS if getattr(opts, f, None) is not None}
    fields["html"] = opts.html
    fields["allow_large_textures"] = opts.allow_large_size
    try:
        _tightex.check_options(Options(**fields))
    except (Error, TypeError) as e:
        ap.error(str(e))
    return fields


def parse_command_line(argv):
    """The tiles command's own options, and the tightex Options fields (a dict) from the tightex flags."""
    ap = argparse.ArgumentParser(prog="python3 -m tightex.tiles", description=__doc__.split("\n")[0],
                                 epilog="tightex options (e.g. --size 1024 --map area) follow INPUT and OUTPUT.")
    ap.add_argument("input", help="a folder of models or a 3D Tiles tileset.json")
    ap.add_argument("output", help="the output folder (mirrors INPUT)")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster here)")
    ap.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core)")
    ap.add_argument("--threads-per-worker", type=int, help="LocalCluster threads per worker (default: cores / workers)")
    ap.add_argument("--tile-threads", type=int,
                    help="threads tightex uses inside a worker process, for all the tiles it runs at once (default with a "
                         "LocalCluster: cores / workers; with --scheduler: all the worker's cores)")
    ap.add_argument("--memory-per-worker", type=float, metavar="MiB",
                    help="LocalCluster: the memory each worker offers tiles (default: this machine's / workers)")
    ap.add_argument("--redo", action="store_true", help="redo tiles an earlier run completed")
    ap.add_argument("--force", action="store_true", dest="force_deprecated", help=argparse.SUPPRESS)  # --redo's former name
    ap.add_argument("--allow-large-size", action="store_true", help="tightex's own --force (a --size above 16384)")
    ap.add_argument("--skip-unreadable", action="store_true",
                    help="contents that are remote, unreadable or refused (listed in the summary) are expected: exit 0 for them")
    ap.add_argument("--html", action="store_true",
                    help="write each tile's report.html too (off by default: a page of several MB per tile; summary.json "
                         "and each tile's report.json hold the figures)")
    _add_tightex_flags(ap)
    opts, unknown = ap.parse_known_args(argv)
    for a in unknown:
        if re.fullmatch(r"-o|--output|--report|--preview|-q|--quiet|-v|--verbose", a.split("=")[0]):
            ap.error(f"{a}: the tiles command sets where each tile's files go and prints its own progress")
    if unknown:
        ap.error(f"unrecognized arguments: {' '.join(unknown)}")
    if opts.force_deprecated:
        print("tightex.tiles: warning: --force is deprecated here: it is --redo (the tightex command's --force, large "
              "textures, is --allow-large-size)", file=sys.stderr)
        opts.redo = True
    return opts, _tightex_options(ap, opts)


def tileset_of_folder(path):
    """``path``/tileset.json where ``path`` is a folder that has one (a 3D Tiles set handed over as its
    folder), else ``path``."""
    tileset = os.path.join(path, "tileset.json")
    return tileset if os.path.isdir(path) and os.path.isfile(tileset) else path


def collect_tiles(opts, output_root):
    """The tiles of INPUT, for a tileset the tilesets to rewrite (else None), and the records of the
    contents not run (NOT_RUN)."""
    from . import InputError
    if os.path.isfile(opts.input) and opts.input.lower().endswith(".json"):
        return read_tileset(opts.input, output_root, opts.allow_outside_files)
    if os.path.isdir(opts.input):
        tiles, refused = folder_tiles(os.path.abspath(opts.input), output_root, opts.allow_outside_files)
        if not tiles and not refused:
            raise InputError(f"{opts.input}: no model file ({', '.join(MODEL_EXTENSIONS)}) under this folder and no tileset.json at its top")
        return None, tiles, refused
    raise InputError(f"{opts.input}: neither a folder of models nor a tileset .json file")


def main(argv=None):
    """The command; returns its exit status."""
    from . import Error, _tightex
    opts, options = parse_command_line(argv)
    opts.input = tileset_of_folder(opts.input)
    start = time.monotonic()
    try:
        output_root = os.path.abspath(opts.output)
        input_root = os.path.dirname(os.path.abspath(opts.input)) if os.path.isfile(opts.input) else os.path.abspath(opts.input)
        if output_root == input_root or output_root.startswith(input_root + os.sep):
            raise _tightex.InputError(f"{opts.output}: the output folder must lie outside the input's")
        tilesets, tiles, not_run = collect_tiles(opts, output_root)
    except Error as e:
        print(f"tightex.tiles: error: {e}", file=sys.stderr)
        return 2
    os.makedirs(output_root, exist_ok=True)
    manifest = {} if opts.redo else read_manifest(output_root)
    records, todo = {r["tile"]: r for r in not_run}, []
    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:  # hashing and tightex's estimate release the GIL
        for tile, settled in zip(tiles, pool.map(lambda t: _prepare(t, manifest, options), tiles)):
            if settled:
                records[tile["id"]] = settled
            else:
                todo.append(tile)
    # Local workers share this machine's cores; an external cluster's workers use their own machine's.
    threads = opts.tile_threads or (None if opts.scheduler else max(1, (os.cpu_count() or 1) // (opts.workers or os.cpu_count() or 1)))
    for tile in todo:
        tile["threads"] = threads
    print(f"tightex.tiles: {len(tiles)} tiles, {len(tiles) - len(todo)} settled by an earlier run (skipped), {len(todo)} to do", file=sys.stderr)
    workers = 0
    if todo:
        client, cluster = _start_client(opts)
        try:
            workers = len(client.scheduler_info().get("workers", {}))
            dashboard = client.dashboard_link if client.run_on_scheduler(_has_bokeh) else None
            print(f"tightex.tiles: {workers} workers; dashboard: "
                  f"{dashboard or 'unavailable (the scheduler runs none: it needs bokeh, which Debian 12 does not package)'}", file=sys.stderr)
            offered = _memory_offered(client)
            if not offered:
                print("tightex.tiles: note: no worker declares the resource \"memory\": tiles run without the memory check",
                      file=sys.stderr)
            records.update(run_tiles(client, todo, options, output_root, offered, len(tiles) - len(todo)))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    if tilesets is not None:
        write_tilesets(tilesets, records, output_root)
    summary = write_summary(output_root, records, time.monotonic() - start, workers)
    for r in sorted(records.values(), key=lambda r: r["tile"]):
        if r["status"] == "failed":
            print(f"tightex.tiles: {r['tile']}: {r['error']}", file=sys.stderr)
        if r["status"] in NOT_RUN:
            print(f"tightex.tiles: {r['status']}: {r['error']}", file=sys.stderr)
        if r["status"] == "passed_through":
            print(f"tightex.tiles: {r['tile']}: passed through: nothing to bake", file=sys.stderr)
    not_run_count = sum(summary[s] for s in NOT_RUN)
    print(f"tightex.tiles: {summary['done']} done, {summary['skipped']} skipped, {summary['passed_through']} passed through "
          f"(nothing to bake), {summary['failed']} failed, {summary['refused']} refused, {summary['remote']} remote, "
          f"{summary['unreadable']} unreadable in "
          f"{summary['wall_seconds']:.1f} s; {os.path.join(opts.output, 'summary.json')}", file=sys.stderr)
    return 1 if summary["failed"] or (not_run_count and not opts.skip_unreadable) else 0


if __name__ == "__main__":
    sys.exit(main())
