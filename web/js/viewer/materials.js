// Shader materials that colour points and meshes by one float attribute through a ramp
// texture, so switching what colours a map (height, intensity, sensor, density, roughness,
// planarity; a change map's M3C2 change, significance, C2C distance) is a uniform change, not
// a pass over millions of points.
import * as THREE from 'three';
import {isCategorical, rampTexels} from './colormap.js';

// `name`: a ramp, or with `categories` > 0 a palette of that many flat colours.
export function rampTexture(name, categories = 0) {
  const texture = new THREE.DataTexture(rampTexels(name, categories), 256, 1, THREE.RGBAFormat);
  texture.magFilter = categories ? THREE.NearestFilter : THREE.LinearFilter;
  texture.minFilter = texture.magFilter;
  texture.needsUpdate = true;
  return texture;
}

// An attribute with a `no_data` value (docs/artifacts.md: just below its smallest defined
// value) colours the points holding it grey: every value below the legend's minimum.
export const NO_NO_DATA = -3.0e38;

// The noDataBelow uniform for a legend: its minimum when the attribute has a no_data value.
export function noDataBelow(legend) {
  return legend.noData !== undefined && !isCategorical(legend.ramp) ? legend.min : NO_NO_DATA;
}

const valueChunk = /* glsl */ `
attribute float value;
uniform float vmin;
uniform float vmax;
uniform int useHeight;
uniform float threshold;
uniform float noDataBelow;
uniform sampler2D ramp;
varying vec3 vColor;
vec3 rampColor() {
#ifdef WORLD_HEIGHT
  float z = (modelMatrix * vec4(position, 1.0)).z;  // tiles keep their offset in the object
#else
  float z = position.z;
#endif
  float v = useHeight == 1 ? z : value;
  if (abs(v) < threshold) return vec3(0.62);
  if (useHeight == 0 && v < noDataBelow) return vec3(0.45);  // a point where the metric is undefined
  float t = clamp((v - vmin) / max(vmax - vmin, 1e-12), 0.0, 1.0);
  return texture2D(ramp, vec2(t, 0.5)).rgb;
}`;

// worldHeight: height colouring takes z after the object's transform (3D tiles place each
// tile's points relative to its corner), else the attribute's own z.
export function pointMaterial({worldHeight = false} = {}) {
  return new THREE.ShaderMaterial({
    defines: worldHeight ? {WORLD_HEIGHT: 1} : {},
    uniforms: {
      vmin: {value: 0}, vmax: {value: 1}, useHeight: {value: 1}, threshold: {value: -1}, noDataBelow: {value: NO_NO_DATA},
      ramp: {value: rampTexture('viridis')}, pointSize: {value: 2},
    },
    vertexShader: `${valueChunk}
uniform float pointSize;
void main() {
  vColor = rampColor();
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
  gl_PointSize = pointSize;
}`,
    fragmentShader: `varying vec3 vColor;
void main() { gl_FragColor = vec4(vColor, 1.0); }`,
  });
}

// A mesh coloured by `value` (or flat grey when `flat`), shaded by the angle between its
// normal and the view direction so its shape reads without lights.
export function meshMaterial({flat = false, opacity = 1} = {}) {
  return new THREE.ShaderMaterial({
    uniforms: {
      vmin: {value: 0}, vmax: {value: 1}, useHeight: {value: 0}, threshold: {value: -1}, noDataBelow: {value: NO_NO_DATA},
      ramp: {value: rampTexture('viridis')}, flatColor: {value: flat ? 1 : 0}, opacity: {value: opacity},
    },
    vertexShader: `${valueChunk}
uniform int flatColor;
varying vec3 vNormal;
void main() {
  vColor = flatColor == 1 ? vec3(0.75) : rampColor();
  vNormal = normalize(normalMatrix * normal);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`,
    fragmentShader: `varying vec3 vColor;
varying vec3 vNormal;
uniform float opacity;
void main() {
  float shade = 0.35 + 0.65 * abs(normalize(vNormal).z);
  gl_FragColor = vec4(vColor * shade, opacity);
}`,
    transparent: opacity < 1,
    depthWrite: opacity >= 1,
    side: THREE.DoubleSide,
  });
}
