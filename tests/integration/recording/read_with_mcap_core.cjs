// Reads an MCAP file with @mcap/core, the format's reference TypeScript reader, twice: indexed
// (summary, chunk indexes, message indexes) and streamed record by record with every CRC
// checked; prints what it found as one JSON line for the test to compare (Recording.*).
//
//   NODE_PATH=/opt/sensornet-node/node_modules node read_with_mcap_core.cjs RUN.mcap
"use strict";
const fs = require("fs");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");

async function main(path) {
  const bytes = fs.readFileSync(path);
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const reader = await McapIndexedReader.Initialize({ readable });
  const indexed = {};
  for await (const m of reader.readMessages()) {
    indexed[m.channelId] = (indexed[m.channelId] ?? 0) + 1;
  }
  const channels = [];
  for (const [id, c] of reader.channelsById) {
    const schema = reader.schemasById.get(c.schemaId);
    channels.push({
      id,
      topic: c.topic,
      messageEncoding: c.messageEncoding,
      metadata: Object.fromEntries(c.metadata),
      schema: schema ? { name: schema.name, encoding: schema.encoding, bytes: schema.data.length } : null,
    });
  }
  const metadata = {};
  for await (const m of reader.readMetadata()) metadata[m.name] = Object.fromEntries(m.metadata);

  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(bytes);
  const streamed = {};
  let record;
  let footer = false;
  while ((record = stream.nextRecord())) {
    if (record.type === "Message") streamed[record.channelId] = (streamed[record.channelId] ?? 0) + 1;
    if (record.type === "Footer") footer = true;
  }
  const s = reader.statistics;
  console.log(JSON.stringify({
    profile: reader.header.profile,
    statistics: s && {
      messageCount: Number(s.messageCount),
      chunkCount: s.chunkCount,
      channelCount: s.channelCount,
      metadataCount: s.metadataCount,
      channelMessageCounts: Object.fromEntries([...s.channelMessageCounts].map(([k, v]) => [k, Number(v)])),
    },
    chunkIndexes: reader.chunkIndexes.length,
    channels,
    indexed,
    streamed,
    streamDone: stream.done(),
    footer,
    metadata,
  }));
}

main(process.argv[2]).catch((e) => {
  console.error(`read_with_mcap_core: ${e && e.message ? e.message : e}`);
  process.exit(1);
});
