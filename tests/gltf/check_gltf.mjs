// Checks glTF/GLB files as a viewer would load them: the Khronos glTF-Validator (errors and warnings
// must be 0) and three.js's GLTFLoader (the scene must load; meshes and triangles are counted).
// Usage: node check_gltf.mjs FILE... ; prints one JSON line per file; exit 1 if any file fails.
import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

// Images are not decoded in node: the loader's texture step fails softly (the texture is null),
// which leaves the geometry and the scene graph to count.
globalThis.self = globalThis;
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};
// EXT_texture_webp: the loader asks an Image whether WebP decodes (every browser it targets says yes);
// node has no Image, so a stand-in answers as a browser does, and the texture itself fails softly.
globalThis.Image ??= class Image {
  set src(_) {
    this.height = 1;
    setTimeout(() => this.onload && this.onload(), 0);
  }
};
const quiet = console.error, warn = console.warn;

async function validate(file, bytes) {
  const report = await validator.validateBytes(new Uint8Array(bytes), {
    uri: path.basename(file),
    maxIssues: 50,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (err, data) => (err ? reject(err.toString()) : resolve(new Uint8Array(data))));
      }),
  });
  return report.issues;
}

async function load(file, bytes) {
  const loader = new GLTFLoader();
  const dir = path.dirname(path.resolve(file)) + '/';
  // External buffers of a .gltf: served from disk through a fetch stand-in.
  globalThis.fetch = async (request) => {
    const url = typeof request === 'string' ? request : request.url;
    const data = fs.readFileSync(decodeURIComponent(new URL(url, 'file://' + dir).pathname));
    return new Response(data);
  };
  console.error = () => {};
  console.warn = () => {};
  try {
    const ab = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
    const gltf = await new Promise((resolve, reject) => loader.parse(ab, 'file://' + dir, resolve, reject));
    let meshes = 0, triangles = 0;
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      meshes++;
      const g = o.geometry;
      triangles += (g.index ? g.index.count : g.attributes.position.count) / 3;
    });
    return { meshes, triangles };
  } finally {
    console.error = quiet;
    console.warn = warn;
  }
}

let failed = false;
for (const file of process.argv.slice(2)) {
  const bytes = fs.readFileSync(file);
  const issues = await validate(file, bytes);
  const result = { file, errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos, hints: issues.numHints };
  result.messages = issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.pointer ?? ''}: ${m.message}`);
  try {
    Object.assign(result, await load(file, bytes));
  } catch (e) {
    result.load_error = String(e && e.message ? e.message : e);
  }
  if (result.errors > 0 || result.warnings > 0 || result.load_error) failed = true;
  console.log(JSON.stringify(result));
}
process.exit(failed ? 1 : 0);
