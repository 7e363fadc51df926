// The browser test's oracles: the distance of a point to a triangle mesh against closed forms,
// and a pose's transform against a known rotation.
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {distanceToMesh, poseTransform} from '../harness.mjs';

const square = {vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], faces: [[0, 1, 2], [0, 2, 3]]};

test('distance to a mesh: above the face, beyond an edge, beyond a corner', () => {
  assert.equal(distanceToMesh([0.3, 0.6, 2], square), 2);
  assert.ok(Math.abs(distanceToMesh([0.5, -3, 4], square) - 5) < 1e-12);        // edge y = 0
  assert.ok(Math.abs(distanceToMesh([2, 3, 2], square) - Math.sqrt(1 + 4 + 4)) < 1e-12);  // corner (1, 1, 0)
  assert.equal(distanceToMesh([0.25, 0.75, 0], square), 0);
});

test('a pose maps the model frame into the world', () => {
  const s = Math.SQRT1_2;
  const T = poseTransform({translation: [10, 0, -1], rotation_xyzw: [0, 0, s, s]});  // 90 deg about z
  const p = T([1, 0, 0]);
  [10, 1, -1].forEach((v, i) => assert.ok(Math.abs(p[i] - v) < 1e-12, `${p}`));
  assert.ok(Math.abs(distanceToMesh([10, 0.5, 1], square, T) - 2) < 1e-12);
});
