"use strict";
// An OPC UA client of another implementation than the server's (node-opcua), as
// tests/test_plant_opcua_node.py drives it:
//
//   node opcua_node_client.js ENDPOINT SPEC_JSON
//
// SPEC (every part optional):
//   target     the folder under Objects/RacConsole (null: the only one there)
//   wait       variables to wait for: there, and their Status no longer WAITING
//   read       variables to read (value, types, status code, timestamps, Status)
//   write      {node, dataType, value}: one write of the Value attribute
//   subscribe  {node, interval, until}: a subscription to the node's value; "subscribed"
//              goes to stderr once its first notification came, then it waits for the
//              value `until`
//   namespace  the server's namespace URI (default urn:rac-console:watched)
//   deadline   seconds for everything (default 30): past it, an error and exit 3
//
// stdout: ONE JSON object (the results, or {"error": ...} and a nonzero exit). Whatever
// node-opcua says goes to stderr.

const NAMESPACE_URI = "urn:rac-console:watched";
const out = process.stdout;
for (const name of ["log", "info", "warn", "debug", "trace"]) {
  console[name] = (...args) => console.error(...args);
}

let done = false;
function finish(code, result) {
  if (done) return;
  done = true;
  out.write(JSON.stringify(result) + "\n", () => process.exit(code));
}

let spec;
try {
  spec = JSON.parse(process.argv[3] || "{}");
} catch (err) {
  finish(2, { error: `bad spec: ${err.message}` });
}
const endpoint = process.argv[2];
const deadline = ((spec && spec.deadline) || 30) * 1000;
const started = Date.now();
const left = () => deadline - (Date.now() - started);
let stage = "loading node-opcua";
setTimeout(() => finish(3, { error: `timed out after ${deadline / 1000} s`, at: stage }), deadline);

let opcua;
try {
  opcua = require("node-opcua-client");
} catch (err) {
  finish(2, { error: `cannot load node-opcua-client: ${err.message}` });
}
const {
  OPCUAClient,
  MessageSecurityMode,
  SecurityPolicy,
  AttributeIds,
  BrowseDirection,
  DataType,
  VariantArrayType,
  NodeClass,
  TimestampsToReturn,
} = opcua || {};

// The standard DataType NodeIds (ns=0) of the types the server uses, and a fallback.
const DATA_TYPES = { 1: "Boolean", 6: "Int32", 10: "Float", 11: "Double", 12: "String" };
function dataTypeName(nodeId) {
  if (!nodeId) return null;
  if (nodeId.namespace === 0 && typeof nodeId.value === "number") {
    return DATA_TYPES[nodeId.value] || DataType[nodeId.value] || nodeId.toString();
  }
  return nodeId.toString();
}

function plain(value) {
  if (ArrayBuffer.isView(value)) return Array.from(value);
  if (Array.isArray(value)) return value.map(plain);
  if (typeof value === "bigint") return value.toString();
  if (value instanceof Date) return value.toISOString();
  return value === undefined ? null : value;
}

function iso(date) {
  return date instanceof Date && !isNaN(date.getTime()) ? date.toISOString() : null;
}

function valueOf(dataValue) {
  const variant = dataValue.value;
  return {
    value: variant ? plain(variant.value) : null,
    variantType: variant ? DataType[variant.dataType] : null,
    arrayType: variant ? VariantArrayType[variant.arrayType] : null,
    statusCode: dataValue.statusCode.name,
    sourceTimestamp: iso(dataValue.sourceTimestamp),
    serverTimestamp: iso(dataValue.serverTimestamp),
  };
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

async function children(session, nodeId, reference) {
  const result = await session.browse({
    nodeId,
    browseDirection: BrowseDirection.Forward,
    referenceTypeId: reference,
    includeSubtypes: true,
    resultMask: 0x3f,
  });
  return (result.references || []).map((ref) => ({
    name: ref.browseName.name,
    namespaceIndex: ref.browseName.namespaceIndex,
    nodeId: ref.nodeId.toString(),
    nodeClass: NodeClass[ref.nodeClass],
  }));
}

async function variables(session, ns, target) {
  // The target's variables as browsed, each with its Status property's NodeId.
  const root = `ns=${ns};s=RacConsole`;
  const folders = await children(session, root, "Organizes");
  let folder;
  if (target == null) {
    if (folders.length !== 1) return { folders, found: null };
    folder = folders[0];
  } else {
    folder = folders.find((f) => f.name === target);
    if (!folder) return { folders, found: null };
  }
  const found = [];
  for (const child of await children(session, folder.nodeId, "HierarchicalReferences")) {
    if (child.nodeClass !== "Variable") {
      found.push(child);
      continue;
    }
    const properties = await children(session, child.nodeId, "HasProperty");
    const status = properties.find((p) => p.name === "Status");
    found.push({ ...child, properties: properties.map((p) => p.name), statusNode: status && status.nodeId });
  }
  return { folders, folder, found };
}

async function describe(session, entry) {
  const ids = [AttributeIds.DataType, AttributeIds.ValueRank, AttributeIds.AccessLevel, AttributeIds.UserAccessLevel];
  const read = await session.read(ids.map((attributeId) => ({ nodeId: entry.nodeId, attributeId })));
  const status = entry.statusNode ? await session.read({ nodeId: entry.statusNode, attributeId: AttributeIds.Value }) : null;
  return {
    name: entry.name,
    namespaceIndex: entry.namespaceIndex,
    nodeId: entry.nodeId,
    nodeClass: entry.nodeClass,
    dataType: dataTypeName(read[0].value.value),
    valueRank: read[1].value.value,
    accessLevel: read[2].value.value,
    userAccessLevel: read[3].value.value,
    properties: entry.properties,
    status: status && status.value ? status.value.value : null,
  };
}

async function main() {
  stage = "connecting";
  const client = OPCUAClient.create({
    applicationName: "rac-console-tests-node-opcua",
    securityMode: MessageSecurityMode.None,
    securityPolicy: SecurityPolicy.None,
    endpointMustExist: false,
    connectionStrategy: { maxRetry: 3, initialDelay: 200, maxDelay: 1000 },
    requestedSessionTimeout: 60000,
  });
  const result = {};
  let session = null;
  let subscription = null;
  try {
    await client.connect(endpoint);
    session = await client.createSession();
    stage = "the namespace";
    const namespaces = await session.readNamespaceArray();
    const uri = spec.namespace || NAMESPACE_URI;
    const ns = namespaces.indexOf(uri);
    if (ns < 0) throw new Error(`no namespace ${uri} in ${JSON.stringify(namespaces)}`);
    result.namespaceIndex = ns;

    stage = "waiting for the variables";
    const wanted = spec.wait || spec.read || [];
    let seen;
    for (;;) {
      seen = await variables(session, ns, spec.target);
      if (seen.found) {
        const byName = Object.fromEntries(seen.found.map((v) => [v.name, v]));
        let ready = wanted.every((name) => byName[name] && byName[name].statusNode);
        for (const name of ready ? wanted : []) {
          const status = await session.read({ nodeId: byName[name].statusNode, attributeId: AttributeIds.Value });
          if (!status.value || status.value.value === "WAITING") ready = false;
        }
        if (ready) break;
      }
      if (left() < 1000) throw new Error(`the variables ${wanted} never came: ${JSON.stringify(seen)}`);
      await sleep(100);
    }
    result.target = seen.folder.name;
    result.folders = seen.folders.map((f) => f.name);
    stage = "browsing";
    result.browse = [];
    for (const entry of seen.found) result.browse.push(await describe(session, entry));
    const nodeOf = (name) => `ns=${ns};s=${seen.folder.name}/${name}`;

    if (spec.read) {
      stage = "reading";
      result.read = {};
      for (const name of spec.read) {
        const dataValue = await session.read({ nodeId: nodeOf(name), attributeId: AttributeIds.Value }, 0);
        result.read[name] = valueOf(dataValue);
      }
    }

    if (spec.write) {
      stage = "writing";
      const { node, dataType, value } = spec.write;
      const statusCode = await session.write({
        nodeId: nodeOf(node),
        attributeId: AttributeIds.Value,
        value: { value: { dataType: DataType[dataType], value } },
      });
      result.write = { statusCode: statusCode.name };
    }

    if (spec.subscribe) {
      stage = "subscribing";
      const { node, interval = 100, until } = spec.subscribe;
      subscription = await session.createSubscription2({
        requestedPublishingInterval: interval,
        requestedLifetimeCount: 600,
        requestedMaxKeepAliveCount: 20,
        maxNotificationsPerPublish: 100,
        publishingEnabled: true,
        priority: 1,
      });
      const notifications = [];
      let wake = () => {};
      const item = await subscription.monitor(
        { nodeId: nodeOf(node), attributeId: AttributeIds.Value },
        { samplingInterval: interval, discardOldest: true, queueSize: 100 },
        TimestampsToReturn.Both
      );
      item.on("changed", (dataValue) => {
        notifications.push(valueOf(dataValue));
        wake();
      });
      const reached = () => notifications.some((n) => JSON.stringify(n.value) === JSON.stringify(until));
      stage = "the first notification";
      while (notifications.length === 0) await new Promise((resolve) => (wake = resolve));
      process.stderr.write("subscribed\n");
      stage = `waiting for ${JSON.stringify(until)}`;
      while (!reached() && left() > 1000) {
        await Promise.race([new Promise((resolve) => (wake = resolve)), sleep(Math.max(0, left() - 1000))]);
      }
      result.subscription = {
        revisedPublishingInterval: subscription.publishingInterval,
        reached: reached(),
        notifications,
      };
    }
    stage = "disconnecting";
  } finally {
    if (subscription) await subscription.terminate().catch(() => {});
    if (session) await session.close().catch(() => {});
    await client.disconnect().catch(() => {});
  }
  return result;
}

if (!done) {
  main().then(
    (result) => finish(0, result),
    (err) => finish(1, { error: String((err && err.message) || err), at: stage })
  );
}
