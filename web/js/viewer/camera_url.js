// The viewer's camera in the page URL (`cam=px,py,pz,tx,ty,tz`: eye and orbit target in
// metres, millimetre precision) so a copied link reopens the same view. Pure (node-tested).

export function encodeCamera(position, target) {
  return [position.x, position.y, position.z, target.x, target.y, target.z]
      .map((v) => Number(v.toFixed(3)).toString()).join(',');
}

// {position: {x,y,z}, target: {x,y,z}} or null when the text is not 6 finite numbers or the
// eye sits on the target.
export function decodeCamera(text) {
  if (typeof text !== 'string') return null;
  const parts = text.split(',');
  if (parts.length !== 6) return null;
  const v = parts.map((p) => (p.trim() === '' ? NaN : Number(p)));
  if (!v.every(Number.isFinite)) return null;
  const position = {x: v[0], y: v[1], z: v[2]};
  const target = {x: v[3], y: v[4], z: v[5]};
  if (position.x === target.x && position.y === target.y && position.z === target.z) return null;
  return {position, target};
}
