// A compare job's 3D artifacts (docs/artifacts.md, compare) from its artifact list: the
// change maps (change_<map>.drc, B's map registered onto A's with the change per point) and
// the change hull (change_hull.drc, B's hull in the CAD model frame), each with its sidecar
// (or null when it is missing). Pure (tested in node).

export const CHANGE_HULL = 'change_hull';

// {maps: [{name, map, full, sidecarArtifact}] (combined first), hull: {name, artifact,
// sidecarArtifact} or null}
export function changesOf(byName) {
  const maps = [];
  for (const fileName of Object.keys(byName)) {
    const match = /^change_(.+)\.drc$/.exec(fileName);
    if (!match || `change_${match[1]}` === CHANGE_HULL) continue;
    const name = `change_${match[1]}`;
    maps.push({name, map: match[1], full: byName[fileName], sidecarArtifact: byName[`${name}.json`] || null});
  }
  maps.sort((a, b) => (a.map === 'combined' ? -1 : b.map === 'combined' ? 1 : a.name.localeCompare(b.name)));
  const hullFile = byName[`${CHANGE_HULL}.drc`];
  const hull = hullFile ? {name: CHANGE_HULL, artifact: hullFile, sidecarArtifact: byName[`${CHANGE_HULL}.json`] || null} : null;
  return {maps, hull};
}
