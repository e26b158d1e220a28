// Reads an MCAP file the way Foxglove does, and checks every message.
//
//   node check_mcap.cjs NODE_MODULES FILE.mcap
//
// The reader is Foxglove's own TypeScript one (@mcap/core's McapIndexedReader,
// which Foxglove's app uses to open local files), with zstd chunks decompressed
// by @foxglove/wasm-zstd (the handler @mcap/support gives Foxglove).  Every
// message must be JSON that validates against its channel's own JSON Schema (the
// one in the file), and a channel whose schema is named foxglove.X must also
// validate against the JSON Schema Foxglove publishes for X (@foxglove/schemas):
// that is what its panels (Log, Image …) read.  Prints one JSON line: the
// channels with their schema and message count, and the problems found.
"use strict";
const fs = require("fs");
const path = require("path");
const { createRequire } = require("module");

const [modules, file] = process.argv.slice(2);
const need = createRequire(path.resolve(modules) + path.sep);
const { McapIndexedReader } = need("@mcap/core");
const zstd = need("@foxglove/wasm-zstd");
const Ajv = need("ajv").default;
const published = need("@foxglove/schemas/jsonschema");

async function main() {
  await zstd.isLoaded;
  const bytes = fs.readFileSync(file);
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({
    readable,
    decompressHandlers: { zstd: (buffer, size) => zstd.decompress(buffer, Number(size)) },
  });
  const ajv = new Ajv({ strict: false, allErrors: true });
  const channels = {}, problems = [], own = new Map(), foxglove = new Map();
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    channels[channel.topic] = { schema: schema.name, encoding: schema.encoding,
      message_encoding: channel.messageEncoding, messages: 0, foxglove_schema: false };
    if (schema.encoding !== "jsonschema" || channel.messageEncoding !== "json") {
      problems.push(`${channel.topic}: ${schema.encoding}/${channel.messageEncoding}, not jsonschema/json`);
      continue;
    }
    own.set(id, ajv.compile(JSON.parse(new TextDecoder().decode(schema.data))));
    if (schema.name.startsWith("foxglove.")) {
      const theirs = published[schema.name.slice("foxglove.".length)];
      if (!theirs) problems.push(`${channel.topic}: Foxglove publishes no schema ${schema.name}`);
      else { foxglove.set(id, ajv.compile(theirs)); channels[channel.topic].foxglove_schema = true; }
    }
  }
  let last = -1n, count = 0;
  for await (const message of reader.readMessages()) {
    const channel = reader.channelsById.get(message.channelId);
    const entry = channels[channel.topic];
    entry.messages++;
    count++;
    if (message.logTime < last) problems.push(`${channel.topic}: messages out of time order`);
    last = message.logTime;
    let value;
    try { value = JSON.parse(new TextDecoder().decode(message.data)); } catch (err) {
      problems.push(`${channel.topic} #${message.sequence}: not JSON: ${err.message}`);
      continue;
    }
    for (const [which, validators] of [["its own schema", own], ["Foxglove's schema", foxglove]]) {
      const validate = validators.get(message.channelId);
      if (validate && !validate(value) && problems.length < 50) {
        problems.push(`${channel.topic} #${message.sequence} against ${which}: ` +
          ajv.errorsText(validate.errors));
      }
    }
  }
  const stats = reader.statistics;
  if (stats && Number(stats.messageCount) !== count) {
    problems.push(`statistics say ${stats.messageCount} messages, ${count} read`);
  }
  process.stdout.write(JSON.stringify({ channels, messages: count, problems,
    chunks: reader.chunkIndexes.length }) + "\n");
}

main().catch((err) => { process.stdout.write(JSON.stringify({ error: String(err && err.stack || err) }) + "\n"); process.exit(1); });
