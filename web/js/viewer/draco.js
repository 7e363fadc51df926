// Decoding Keel's Draco files (docs/artifacts.md) with three's DRACOLoader: its WebAssembly
// decoder runs in a worker, so a big map never blocks the page while it decodes. GENERIC
// attributes are found by the unique ids the sidecar lists (DRACOLoader cannot find them by
// name); POSITION by the sidecar's `position_unique_id`, else 0 (Draco numbers attributes
// from 0 in the order they are added, and Keel's writers add positions first).
import {DRACOLoader} from 'three/addons/loaders/DRACOLoader.js';

let loader = null;

function dracoLoader() {
  if (!loader) {
    loader = new DRACOLoader();
    loader.setDecoderConfig({type: 'wasm'});
    // Two cores: one decoder worker leaves the other for the page and the GPU process.
    loader.setWorkerLimit(1);
  }
  return loader;
}

// The attributes a sidecar names, for DRACOLoader.decodeGeometry.
export function taskConfigFor(sidecar) {
  const attributeIDs = {position: Number.isInteger(sidecar?.position_unique_id) ? sidecar.position_unique_id : 0};
  const attributeTypes = {position: 'Float32Array'};
  for (const [name, info] of Object.entries(sidecar?.attributes || {})) {
    if (!Number.isInteger(info?.unique_id) || name === 'position') continue;
    attributeIDs[name] = info.unique_id;
    attributeTypes[name] = 'Float32Array';
  }
  return {attributeIDs, attributeTypes, useUniqueIDs: true, vertexColorSpace: ''};
}

// A BufferGeometry with `position` and one float attribute per sidecar attribute. Without a
// sidecar only the position is decoded. Rejects with a message naming `fileName`.
export async function decodeDraco(buffer, sidecar, fileName) {
  const config = taskConfigFor(sidecar);
  try {
    return await dracoLoader().decodeGeometry(buffer, config);
  } catch (e) {
    const why = String(e?.message || e).replace(/^THREE\.DRACOLoader: /, '');
    throw new Error(`${fileName} could not be decoded as Draco (${why})`);
  }
}
