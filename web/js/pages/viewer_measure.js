// The viewer's measurements (viewer.js's "Measure" panel section): point to point, and from a
// point to the CAD model's surface, on what the cursor picks on the visible maps, hull and
// residuals. Each measurement is drawn (markers, a segment), listed, and kept in
// state.measurements for tests. Called by viewer.js with the page's shared parts.
import * as THREE from 'three';
import {h} from '../dom.js';
import {formatNumber} from '../format.js';
import {MeshLayer} from '../viewer/mesh_layer.js';
import {PointCloudLayer} from '../viewer/point_cloud_layer.js';
import {ResidualLayer} from '../viewer/residual_layer.js';

export function setupMeasure({section, layers, state, scene, canvas, readout, measureGroup}) {
  const el = section('measure', 'Measure');
  const results = h('ol', {id: 'measurements'});
  const mode = (name, label) => h('button', {type: 'button', class: 'measure-mode', dataset: {mode: name}, on: {click: () => {
    state.measure = state.measure?.mode === name ? null : {mode: name, first: null};
    for (const b of el.querySelectorAll('button.measure-mode')) b.classList.toggle('active', b.dataset.mode === state.measure?.mode);
    readout.hidden = !state.measure;
    readout.textContent = state.measure ? (name === 'distance' ? 'Click the first point' : 'Click a point to measure its distance to the CAD model') : '';
  }}}, label);
  el.append(h('div', {class: 'toolbar'}, mode('distance', 'Point to point'),
              layers.has('cad_model') ? mode('cad', 'Point to CAD') : null,
              h('button', {type: 'button', on: {click: () => {
                measureGroup.clear();
                results.replaceChildren();
                state.measurements = [];
                scene.requestRender();
              }}}, 'Clear')), results);
  let down = null;
  canvas.addEventListener('pointerdown', (e) => { down = {x: e.clientX, y: e.clientY}; });
  canvas.addEventListener('pointerup', (e) => {
    if (!state.measure || !down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > 4) return;
    measureAt(e.clientX, e.clientY, results);
  });

  function marker(point, color) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(1, 12, 8), new THREE.MeshBasicMaterial({color}));
    const scale = scene.camera.position.distanceTo(scene.controls.target) / 150;
    m.scale.setScalar(scale);
    m.position.copy(point);
    measureGroup.add(m);
  }

  function segment(a, b, color) {
    const geometry = new THREE.BufferGeometry().setFromPoints([a, b]);
    const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({color, depthTest: false}));
    line.renderOrder = 10;
    measureGroup.add(line);
  }

  // Picks the point under the cursor on the visible maps, hull and trajectories.
  function pickAt(x, y) {
    const objects = [];
    for (const layer of layers.values()) {
      if (!layer.object3d.visible || layer.status !== 'shown') continue;
      if (layer instanceof PointCloudLayer && layer.coarse)
        objects.push(...(state.interacting || !layer.details.length ? [layer.coarse] : layer.details));
      if (layer.isTiles && layer.tiles) objects.push(layer.tiles.group);
      if (layer instanceof MeshLayer && layer.mesh && layer.kind !== 'cad') objects.push(layer.mesh);
      if (layer instanceof ResidualLayer) objects.push(layer.points);
    }
    const threshold = scene.camera.position.distanceTo(scene.controls.target) / 300;
    return scene.pick(x, y, objects, threshold);
  }

  async function measureAt(x, y, results) {
    const hit = pickAt(x, y);
    if (!hit) {
      readout.textContent = 'No point there: click on a map or the hull';
      return;
    }
    const p = hit.point.clone();
    if (state.measure.mode === 'distance') {
      if (!state.measure.first) {
        state.measure.first = p;
        marker(p, 0xffeb3b);
        readout.textContent = 'Click the second point';
      } else {
        const a = state.measure.first;
        marker(p, 0xffeb3b);
        segment(a, p, 0xffeb3b);
        const d = a.distanceTo(p);
        const text = `${formatNumber(d, 4)} m (Δ ${formatNumber(p.x - a.x, 3)}, ${formatNumber(p.y - a.y, 3)}, ${formatNumber(p.z - a.z, 3)})`;
        state.measurements.push({kind: 'distance', metres: d, from: a.toArray(), to: p.toArray()});
        results.append(h('li', {dataset: {kind: 'distance', metres: String(d)}}, `point to point: ${text}`));
        readout.textContent = text;
        state.measure.first = null;
      }
    } else {
      const cad = layers.get('cad_model');
      if (cad.status === 'idle') {
        readout.textContent = 'Loading the CAD model…';
        await cad.load();
      }
      if (cad.status !== 'shown') {
        readout.textContent = `The CAD model cannot be used: ${cad.message}`;
        return;
      }
      const closest = cad.closestPoint(p);
      marker(p, 0x00e5ff);
      segment(p, closest.point, 0x00e5ff);
      const text = `${formatNumber(closest.distance, 4)} m to the CAD surface`;
      state.measurements.push({kind: 'cad', metres: closest.distance, from: p.toArray(), to: closest.point.toArray()});
      results.append(h('li', {dataset: {kind: 'cad', metres: String(closest.distance)}}, text));
      readout.textContent = text;
    }
    scene.requestRender();
  }
}
