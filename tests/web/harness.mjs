// Real Keel processes on loopback and a headless Chromium for the browser tests and the web
// benchmark: keel-sim writes missions, keel-server (with local keel-workers) serves the API
// and the dashboard, the `keel` CLI submits, playwright-core drives Debian's chromium.
import {spawn, spawnSync} from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import {createRequire} from 'node:module';
import {fileURLToPath} from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
export const sourceDir = path.resolve(here, '../..');
export const CHROMIUM = process.env.KEEL_CHROMIUM || '/usr/bin/chromium';

export function parseArgs(argv) {
  const args = {};
  for (let i = 0; i < argv.length; i += 1)
    if (argv[i].startsWith('--')) args[argv[i].slice(2)] = i + 1 === argv.length || argv[i + 1].startsWith('--') ? 'true' : argv[++i];
  return args;
}

// Why the browser tests cannot run here, or '' when they can.
export function missingPrerequisite(binDir, webDir) {
  if (!fs.existsSync(CHROMIUM)) return `no Chromium at ${CHROMIUM} (deploy/setup.sh installs Debian's chromium)`;
  if (!fs.existsSync(path.join(sourceDir, 'web/node_modules/playwright-core')))
    return 'web/node_modules has no playwright-core (deploy/setup.sh runs npm ci in web/)';
  if (!fs.existsSync(path.join(webDir, 'index.html'))) return `no dashboard in ${webDir} (build the keel_web target)`;
  if (!fs.readdirSync(path.join(webDir, 'vendor')).some((d) => d.startsWith('three-') && d !== 'three-missing'))
    return `${webDir}/vendor has no three.js (npm ci in web/, then rebuild)`;
  for (const p of ['keel-server', 'keel-worker', 'keel', 'keel-sim'])
    if (!fs.existsSync(path.join(binDir, p))) return `no ${p} in ${binDir}`;
  return '';
}

export function playwright() {
  const require = createRequire(path.join(sourceDir, 'web/package.json'));
  return require('playwright-core');
}

export function tempDir(prefix = 'keel-web-') {
  return fs.mkdtempSync(path.join(os.tmpdir(), prefix));
}

function exitError(binary, args, status, signal, stdout, stderr) {
  return new Error(`${path.basename(binary)} ${args.join(' ')} exited ${status}${signal ? ` (${signal})` : ''}:\n${stdout}\n${stderr}`);
}

export function run(binary, args, {env = {}, timeoutMs = 600000} = {}) {
  const r = spawnSync(binary, args, {env: {...process.env, ...env}, encoding: 'utf8', timeout: timeoutMs});
  if (r.status !== 0) throw exitError(binary, args, r.status, r.signal, r.stdout, r.stderr);
  return r.stdout.trim();
}

// run() without blocking this process: pages keep being driven while the program runs.
export function runAsync(binary, args, {env = {}, timeoutMs = 600000} = {}) {
  return new Promise((resolve, reject) => {
    const child = spawn(binary, args, {env: {...process.env, ...env}, timeout: timeoutMs});
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; });
    child.on('error', reject);
    child.on('close', (status, signal) => (status === 0 ? resolve(stdout.trim()) : reject(exitError(binary, args, status, signal, stdout, stderr))));
  });
}

// survey: 1 = the first survey of a scene, 2, 3, ... the same scene again with known changes
// (usv-bridge, hauv-hull); left out, keel-sim's default (the first).
function simulateArgs(out, {scenario = 'usv-bridge', duration = 20, sensors = '', seed = 1, survey, set = []}) {
  const args = ['--scenario', scenario, '--seed', String(seed), '--duration', String(duration), '--out', out];
  if (survey !== undefined) args.push('--survey', String(survey));
  if (sensors) args.push('--sensors', sensors);
  for (const s of set) args.push('--set', s);
  return args;
}

export function simulate(binDir, out, options = {}) {
  run(path.join(binDir, 'keel-sim'), simulateArgs(out, options));
  return out;
}

export async function simulateAsync(binDir, out, options = {}) {
  await runAsync(path.join(binDir, 'keel-sim'), simulateArgs(out, options));
  return out;
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

function jobIdIn(out) {
  const match = /j_[0-9a-f]+/.exec(out);
  if (!match) throw new Error(`no job id in: ${out}`);
  return match[0];
}

// Servers this process started, stopped even when a test or benchmark dies with an error.
const started = new Set();
process.on('exit', () => {
  for (const child of started) if (child.exitCode === null) child.kill('SIGKILL');
});

export class Server {
  // serverArgs: more keel-server options (a benchmark that makes 1,000 jobs at once turns
  // the per-token request rate limit off with ['--rate-limit', '0']).
  constructor(binDir, webDir, {workers = 1, dataDir = tempDir('keel-web-data-'), serverArgs = []} = {}) {
    this.binDir = binDir;
    this.serverArgs = serverArgs;
    this.webDir = webDir;
    this.workers = workers;
    this.dataDir = dataDir;
    this.log = path.join(dataDir, 'server.log');
  }

  async start() {
    fs.rmSync(path.join(this.dataDir, 'server.url'), {force: true});  // a reused folder's old one
    const log = fs.openSync(this.log, 'a');
    this.process = spawn(path.join(this.binDir, 'keel-server'),
      ['--data-dir', this.dataDir, '--listen', '127.0.0.1:0', '--workers', String(this.workers), '--web-dir', this.webDir, ...this.serverArgs],
      {stdio: ['ignore', log, log]});
    started.add(this.process);
    const urlFile = path.join(this.dataDir, 'server.url');
    for (let i = 0; i < 300; i += 1) {
      const nonEmpty = (f) => fs.existsSync(f) && fs.statSync(f).size > 0;
      if (nonEmpty(urlFile) && nonEmpty(path.join(this.dataDir, 'token'))) break;
      if (this.process.exitCode !== null) throw new Error(`keel-server exited: ${fs.readFileSync(this.log, 'utf8')}`);
      await sleep(100);
    }
    this.url = fs.readFileSync(urlFile, 'utf8').trim();
    this.token = fs.readFileSync(path.join(this.dataDir, 'token'), 'utf8').trim();
    return this;
  }

  env() {
    return {KEEL_URL: this.url, KEEL_TOKEN_FILE: path.join(this.dataDir, 'token')};
  }

  keel(args, options = {}) {
    return run(path.join(this.binDir, 'keel'), args, {env: this.env(), ...options});
  }

  // Submits a mission folder with the CLI; returns the job id.
  submit(missionDir, stages, extra = []) {
    return jobIdIn(this.keel(['submit', missionDir, '--stages', stages, '-q', ...extra]));
  }

  // submit() without blocking this process (the upload of a mission takes seconds).
  async submitAsync(missionDir, stages, extra = []) {
    return jobIdIn(await runAsync(path.join(this.binDir, 'keel'), ['submit', missionDir, '--stages', stages, '-q', ...extra], {env: this.env()}));
  }

  async api(pathname, {method = 'GET', json, token = this.token, raw = false} = {}) {
    const send = () => fetch(`${this.url}/${pathname}`, {method, headers: {Authorization: `Bearer ${token}`,
      ...(json ? {'Content-Type': 'application/json'} : {})}, body: json ? JSON.stringify(json) : undefined});
    let response;
    try {
      response = await send();
    } catch (e) {
      // The server closes a keep-alive connection idle for its read timeout (30 s); when that
      // happens while this process is blocked in spawnSync (keel-sim, the keel CLI), fetch
      // can reuse the closed connection ("other side closed"). A GET is sent again.
      if (e?.cause?.code !== 'UND_ERR_SOCKET' || (method !== 'GET' && method !== 'HEAD')) throw e;
      response = await send();
    }
    if (raw) return response;
    const text = await response.text();
    if (!response.ok) throw new Error(`${method} ${pathname}: ${response.status} ${text}`);
    return text ? JSON.parse(text) : null;
  }

  async waitJob(id, done = (job) => ['succeeded', 'failed', 'canceled'].includes(job.state), timeoutMs = 600000) {
    const end = Date.now() + timeoutMs;
    for (;;) {
      const job = await this.api(`v1/jobs/${id}`);
      if (done(job)) return job;
      if (Date.now() > end) throw new Error(`job ${id} still ${job.state} after ${timeoutMs / 1000} s`);
      await sleep(250);
    }
  }

  async artifacts(id) {
    const {artifacts} = await this.api(`v1/jobs/${id}/artifacts`);
    return Object.fromEntries(artifacts.map((a) => [a.name, a]));
  }

  async artifactBytes(artifact) {
    const response = await this.api(`v1/artifacts/${artifact.id}`, {raw: true});
    if (!response.ok) throw new Error(`artifact ${artifact.name}: ${response.status}`);
    return Buffer.from(await response.arrayBuffer());
  }

  // One member of a tar artifact (GET /v1/artifacts/{id}/files/{path}), as bytes.
  async artifactFile(artifact, member) {
    const response = await this.api(`v1/artifacts/${artifact.id}/files/${member}`, {raw: true});
    if (!response.ok) throw new Error(`${artifact.name}/${member}: HTTP ${response.status}`);
    return Buffer.from(await response.arrayBuffer());
  }

  async artifactJson(artifact) {
    return JSON.parse((await this.artifactBytes(artifact)).toString('utf8'));
  }

  async stop() {
    if (!this.process || this.process.exitCode !== null) return;
    this.process.kill('SIGTERM');
    for (let i = 0; i < 100 && this.process.exitCode === null; i += 1) await sleep(100);
    if (this.process.exitCode === null) this.process.kill('SIGKILL');
  }
}

export const CHROMIUM_ARGS = ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--headless',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
  '--disable-default-apps', '--mute-audio'];

// A Chromium with a fresh profile folder (removed by close()).
export async function launchChromium() {
  const {chromium} = playwright();
  const profile = tempDir('keel-chromium-');
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: CHROMIUM_ARGS, viewport: {width: 1400, height: 900},
  });
  return {context, close: async () => {
    await context.close();
    fs.rmSync(profile, {recursive: true, force: true});
  }};
}

// Records console errors, page errors, failed requests and HTTP errors of a page.
// `allowStatus(response)` names answers the test expects (Chromium also logs each as a
// console error, which is then allowed too).
export function watchPage(page, {allowStatus = () => false} = {}) {
  const problems = [];
  const allowedUrls = new Set();
  page.on('console', (m) => {
    if (m.type() !== 'error') return;
    if (m.text().startsWith('Failed to load resource') && allowedUrls.has(m.location()?.url)) return;
    problems.push(`console error: ${m.text()} (${m.location()?.url || ''})`);
  });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('requestfailed', (r) => {
    const why = r.failure()?.errorText || '';
    // A stream or download the page itself stops when it moves on is not a failure.
    if (why.includes('ERR_ABORTED')) return;
    problems.push(`request failed: ${r.method()} ${r.url()} ${why}`);
  });
  page.on('response', (r) => {
    if (r.status() >= 400 && allowStatus(r)) allowedUrls.add(r.url());
    else if (r.status() >= 400) problems.push(`HTTP ${r.status()}: ${r.request().method()} ${r.url()}`);
  });
  return problems;
}

// The number of vertices of a Draco file as Debian's draco_decoder (an independent decoder)
// reads it, or null when the tool is absent.
export function dracoVertexCount(bytes) {
  return dracoDecoded(bytes, 'ply', (out) => {
    const match = /element vertex (\d+)/.exec(fs.readFileSync(out).subarray(0, 4096).toString('latin1'));
    return match ? Number(match[1]) : null;
  });
}

// `read(file)` of the file draco_decoder writes from `bytes` (its format by `extension`), or
// null when the tool is absent.
function dracoDecoded(bytes, extension, read) {
  const tool = '/usr/bin/draco_decoder';
  if (!fs.existsSync(tool)) return null;
  const dir = tempDir('keel-draco-');
  try {
    fs.writeFileSync(path.join(dir, 'in.drc'), bytes);
    run(tool, ['-i', path.join(dir, 'in.drc'), '-o', path.join(dir, `out.${extension}`)]);
    return read(path.join(dir, `out.${extension}`));
  } finally {
    fs.rmSync(dir, {recursive: true, force: true});
  }
}

// A 3D Tiles point-cloud tile (.pnts) read as the 3D Tiles 1.0 spec lays it out (28-byte
// header, feature table JSON, then its binary body): its point count and the z range of its
// points (POSITION_QUANTIZED: offset + q / 65535 * scale, or float POSITION).
export function readPnts(bytes) {
  const buffer = Buffer.from(bytes);
  if (buffer.length < 28 || buffer.toString('latin1', 0, 4) !== 'pnts') throw new Error('not a .pnts tile');
  const jsonLength = buffer.readUInt32LE(12);
  const table = JSON.parse(buffer.toString('utf8', 28, 28 + jsonLength));
  const body = 28 + jsonLength;
  const points = table.POINTS_LENGTH;
  let zMin = Infinity;
  let zMax = -Infinity;
  for (let i = 0; i < points; i += 1) {
    const z = table.POSITION_QUANTIZED
      ? table.QUANTIZED_VOLUME_OFFSET[2] + buffer.readUInt16LE(body + table.POSITION_QUANTIZED.byteOffset + 6 * i + 4) / 65535 * table.QUANTIZED_VOLUME_SCALE[2]
      : buffer.readFloatLE(body + table.POSITION.byteOffset + 12 * i + 8);
    zMin = Math.min(zMin, z);
    zMax = Math.max(zMax, z);
  }
  return {points, zMin, zMax};
}

// A Draco mesh as Debian's draco_decoder reads it (an independent decoder), as an OBJ:
// {vertices: [[x, y, z]...], faces: [[i, j, k]...]} (0-based), or null when the tool is absent.
export function dracoMesh(bytes) {
  return dracoDecoded(bytes, 'obj', (out) => {
    const vertices = [];
    const faces = [];
    for (const line of fs.readFileSync(out, 'utf8').split('\n')) {
      const f = line.trim().split(/\s+/);
      if (f[0] === 'v') vertices.push(f.slice(1, 4).map(Number));
      if (f[0] === 'f') faces.push(f.slice(1, 4).map((x) => Number(x.split('/')[0]) - 1));
    }
    return {vertices, faces};
  });
}

// The point of triangle abc closest to p (Ericson, Real-Time Collision Detection, 5.1.5).
function closestOnTriangle(p, a, b, c) {
  const sub = (u, v) => [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
  const dot = (u, v) => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const at = (o, u, s, v = [0, 0, 0], t = 0) => [0, 1, 2].map((i) => o[i] + s * u[i] + t * v[i]);
  const ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const bp = sub(p, b), d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(a, ab, d1 / (d1 - d3));
  const cp = sub(p, c), d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(a, ac, d2 / (d2 - d6));
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return at(b, sub(c, b), (d4 - d3) / (d4 - d3 + d5 - d6));
  const denom = 1 / (va + vb + vc);
  return at(a, ab, vb * denom, ac, vc * denom);
}

// The distance from p to a mesh ({vertices, faces}) by brute force over every triangle, the
// vertices first mapped by `transform(v)` (e.g. the CAD model frame into the world).
export function distanceToMesh(p, mesh, transform = (v) => v) {
  const v = mesh.vertices.map(transform);
  let best = Infinity;
  for (const [i, j, k] of mesh.faces) {
    const q = closestOnTriangle(p, v[i], v[j], v[k]);
    best = Math.min(best, Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
  }
  return best;
}

// x -> R x + t for a pose {translation: [x, y, z], rotation_xyzw: [x, y, z, w]}.
export function poseTransform({translation, rotation_xyzw: [x, y, z, w]}) {
  const n = Math.hypot(x, y, z, w);
  [x, y, z, w] = [x / n, y / n, z / n, w / n];
  const R = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]];
  return (p) => R.map((row, i) => row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + translation[i]);
}
