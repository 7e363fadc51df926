// Which maps the viewer draws from their level-of-detail tiles (tiles_<map>.tar) rather than
// from their Draco file: a map bigger than the point budget, whose Draco file would have to
// be downloaded and decoded whole before its first picture. Pure (tested in node).

// Without a sidecar to give the point count, a Draco map over this size counts as big (Keel's
// Draco maps take 2.5-3 bytes a point: about three million points).
export const BIG_DRACO_BYTES = 8 * 2 ** 20;

// map: {full: artifact, tiles: artifact or null}; sidecar: the Draco sidecar or null;
// lod: 'auto' (by size), 'tiles' or 'draco' (the URL's ?lod=).
export function useTiles(map, sidecar, {lod = 'auto', budget}) {
  if (!map.tiles || lod === 'draco') return false;
  if (lod === 'tiles') return true;
  return Number.isFinite(sidecar?.points) ? sidecar.points > budget : map.full.size > BIG_DRACO_BYTES;
}
