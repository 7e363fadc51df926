// Even thinning of decoded point attributes by a stride, done attribute by attribute with a
// pause between them so the page never blocks for long on a big map. Draco's point-cloud
// encoder stores points in kd-tree order, so every k-th point is spread over the whole map.
import * as THREE from 'three';

export function strideFor(count, budget) {
  return count > budget ? Math.ceil(count / budget) : 1;
}

const pause = () => new Promise((resolve) => setTimeout(resolve, 0));

// Every `stride`-th element group of a typed array (`itemSize` values per point).
export function strided(array, itemSize, stride) {
  const count = Math.floor((array.length / itemSize + stride - 1) / stride);
  const out = new array.constructor(count * itemSize);
  for (let i = 0, j = 0; j < out.length; i += stride * itemSize, j += itemSize)
    for (let k = 0; k < itemSize; k += 1) out[j + k] = array[i + k];
  return out;
}

// A new geometry with every `stride`-th point of `geometry` (all its attributes).
export async function thinGeometry(geometry, stride) {
  const out = new THREE.BufferGeometry();
  for (const [name, attribute] of Object.entries(geometry.attributes)) {
    const array = attribute.array;
    out.setAttribute(name, new THREE.BufferAttribute(
        stride === 1 ? array : strided(array, attribute.itemSize, stride), attribute.itemSize));
    if (stride > 1 && array.length > 3e6) await pause();
  }
  return out;
}
