// Validates deploy/k8s/*.yaml against the Kubernetes OpenAPI schemas and KEDA's CRD schemas
// (as compiled by the npm packages kubernetes-models and @kubernetes-models/keda), plus the
// cross-object rules the API server enforces that a schema cannot say (a Deployment's
// selector matches its pod labels, every volumeMount names a volume) and the ones this
// deployment needs (Service, PodDisruptionBudget and ScaledObject reach a Deployment).
// Then it checks that it would notice: broken copies of the manifests must be refused.
//   node tests/deploy/validate_k8s.mjs deploy/k8s
import fs from "node:fs";
import path from "node:path";
import { parseAllDocuments } from "yaml";

const modules = {
  "v1": "kubernetes-models/v1",
  "apps/v1": "kubernetes-models/apps/v1",
  "policy/v1": "kubernetes-models/policy/v1",
  "keda.sh/v1alpha1": "@kubernetes-models/keda/keda.sh/v1alpha1",
};

async function schemaErrors(doc) {
  const where = `${doc.kind ?? "?"}/${doc.metadata?.name ?? "?"}`;
  const module = modules[doc.apiVersion];
  if (!module) return [`${where}: apiVersion '${doc.apiVersion}' is not one Keel uses`];
  const Model = (await import(module))[doc.kind];
  if (!Model) return [`${where}: no kind '${doc.kind}' in ${doc.apiVersion}`];
  try {
    new Model(doc).validate();
    return [];
  } catch (error) {
    return [`${where}: ${error.message}`];
  }
}

const matches = (selector, labels) =>
  Object.entries(selector ?? {}).every(([key, value]) => labels?.[key] === value);

function crossErrors(docs) {
  const errors = [];
  const deployments = docs.filter((d) => d.kind === "Deployment");
  for (const d of deployments) {
    const labels = d.spec?.template?.metadata?.labels;
    if (!matches(d.spec?.selector?.matchLabels, labels) || !d.spec?.selector?.matchLabels)
      errors.push(`Deployment/${d.metadata.name}: selector does not match the pod labels`);
    const volumes = new Set((d.spec?.template?.spec?.volumes ?? []).map((v) => v.name));
    for (const c of d.spec?.template?.spec?.containers ?? [])
      for (const m of c.volumeMounts ?? [])
        if (!volumes.has(m.name))
          errors.push(`Deployment/${d.metadata.name}: mount '${m.name}' names no volume`);
  }
  const podsOf = (selector) =>
    deployments.filter((d) => selector && matches(selector, d.spec?.template?.metadata?.labels));
  for (const s of docs.filter((d) => d.kind === "Service"))
    if (podsOf(s.spec?.selector).length === 0)
      errors.push(`Service/${s.metadata.name}: selector reaches no Deployment's pods`);
  for (const p of docs.filter((d) => d.kind === "PodDisruptionBudget"))
    if (podsOf(p.spec?.selector?.matchLabels).length === 0)
      errors.push(`PodDisruptionBudget/${p.metadata.name}: selector reaches no pods`);
  const auths = new Set(docs.filter((d) => d.kind === "TriggerAuthentication").map((d) => d.metadata.name));
  for (const o of docs.filter((d) => d.kind === "ScaledObject")) {
    if (!deployments.some((d) => d.metadata.name === o.spec?.scaleTargetRef?.name))
      errors.push(`ScaledObject/${o.metadata.name}: scaleTargetRef names no Deployment`);
    for (const t of o.spec?.triggers ?? [])
      if (t.authenticationRef && !auths.has(t.authenticationRef.name))
        errors.push(`ScaledObject/${o.metadata.name}: no TriggerAuthentication '${t.authenticationRef.name}'`);
  }
  const claims = new Set(docs.filter((d) => d.kind === "PersistentVolumeClaim").map((d) => d.metadata.name));
  for (const d of deployments)
    for (const v of d.spec?.template?.spec?.volumes ?? [])
      if (v.persistentVolumeClaim && !claims.has(v.persistentVolumeClaim.claimName))
        errors.push(`Deployment/${d.metadata.name}: no PersistentVolumeClaim '${v.persistentVolumeClaim.claimName}'`);
  return errors;
}

async function check(docs) {
  const errors = [];
  for (const doc of docs) errors.push(...(await schemaErrors(doc)));
  return errors.concat(crossErrors(docs));
}

const folder = process.argv[2] ?? "deploy/k8s";
const docs = [];
for (const file of fs.readdirSync(folder).filter((f) => f.endsWith(".yaml")).sort()) {
  for (const doc of parseAllDocuments(fs.readFileSync(path.join(folder, file), "utf8"))) {
    if (doc.errors.length) {
      console.error(`${file}: YAML: ${doc.errors[0].message}`);
      process.exit(1);
    }
    if (doc.contents !== null) docs.push(doc.toJSON());
  }
}
const kinds = docs.map((d) => d.kind).sort().join(", ");
const errors = await check(docs);
for (const e of errors) console.error(e);
console.log(`${docs.length} objects (${kinds}): ${errors.length} errors`);

// Broken copies must be refused, or this check proves nothing.
const clone = () => structuredClone(docs);
const find = (all, kind, name) => all.find((d) => d.kind === kind && d.metadata.name === name);
const breakages = {
  "replicas as a string": (all) => { find(all, "Deployment", "keel-server").spec.replicas = "two"; },
  "no selector": (all) => { delete find(all, "Deployment", "keel-worker").spec.selector; },
  "container without a name": (all) => { delete find(all, "Deployment", "keel-server").spec.template.spec.containers[0].name; },
  "unknown access mode": (all) => { find(all, "PersistentVolumeClaim", "keel-blobs").spec.accessModes = 5; },
  "ScaledObject without triggers": (all) => { delete find(all, "ScaledObject", "keel-worker").spec.triggers; },
  "ScaledObject on a missing Deployment": (all) => { find(all, "ScaledObject", "keel-worker").spec.scaleTargetRef.name = "nope"; },
  "selector apart from the pod labels": (all) => { find(all, "Deployment", "keel-server").spec.selector.matchLabels["x"] = "y"; },
  "mount of no volume": (all) => { find(all, "Deployment", "keel-worker").spec.template.spec.volumes.pop(); },
};
let unnoticed = 0;
for (const [what, breakIt] of Object.entries(breakages)) {
  const broken = clone();
  breakIt(broken);
  if ((await check(broken)).length === 0) {
    console.error(`a broken copy passed: ${what}`);
    ++unnoticed;
  }
}
console.log(`${Object.keys(breakages).length - unnoticed} of ${Object.keys(breakages).length} broken copies refused`);
process.exit(errors.length === 0 && unnoticed === 0 ? 0 : 1);
