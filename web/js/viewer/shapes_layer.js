// The shapes the inspect stage found (shapes.json: centroid, min/max corners in the world
// frame) as boxes; the viewer flies to one when its row in the shapes table is clicked.
import * as THREE from 'three';

export function validateShapes(doc, fileName) {
  if (!doc || !Array.isArray(doc.shapes)) throw new Error(`${fileName}: no "shapes" list`);
  doc.shapes.forEach((s, i) => {
    for (const key of ['centroid_world_m', 'min_world_m', 'max_world_m'])
      if (!Array.isArray(s[key]) || s[key].length !== 3 || !s[key].every(Number.isFinite))
        throw new Error(`${fileName}: shapes[${i}].${key} must be 3 numbers`);
  });
  return doc;
}

export class ShapesLayer {
  constructor(doc) {
    this.name = 'shapes';
    this.shapes = doc.shapes;
    this.object3d = new THREE.Group();
    this.object3d.name = 'shapes';
    this.status = 'shown';
    this.message = '';
    this.boxes = this.shapes.map((shape) => {
      const box = new THREE.Box3(new THREE.Vector3(...shape.min_world_m), new THREE.Vector3(...shape.max_world_m));
      // A flat shape still gets a visible box.
      box.expandByScalar(0.01);
      const helper = new THREE.Box3Helper(box, 0xff4081);
      helper.userData.shapeId = shape.id;
      this.object3d.add(helper);
      return box;
    });
  }

  // {center, distance}: where the camera goes to look at shape i.
  viewOf(i) {
    const box = this.boxes[i];
    const center = new THREE.Vector3(...this.shapes[i].centroid_world_m);
    const size = box.getSize(new THREE.Vector3()).length();
    return {center, distance: Math.max(1.5, size * 3)};
  }

  highlight(i) {
    this.object3d.children.forEach((helper, k) => helper.material.color.set(k === i ? 0xffeb3b : 0xff4081));
  }

  boundingBox() {
    const box = new THREE.Box3();
    for (const b of this.boxes) box.union(b);
    return box.isEmpty() ? null : box;
  }

  dispose() {
    for (const helper of this.object3d.children) {
      helper.geometry.dispose();
      helper.material.dispose();
    }
  }
}
