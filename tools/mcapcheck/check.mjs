// An independent check of an MCAP file that `afford export` wrote, with Foxglove's own
// reader (@mcap/core) and a zstd decoder written in JavaScript (fzstd), both pinned in
// package.json (`npm ci --prefix tools/mcapcheck` installs them):
//
//   node tools/mcapcheck/check.mjs FILE [--digest]
//
// 1. McapStreamReader (validateCrcs) reads every record from the start: the Header first, the
//    data section (Schemas, Channels and Messages only inside Chunks; each Chunk followed by one
//    MessageIndex per channel it holds, whose entries point at its messages, each once), DataEnd,
//    then a summary of Schemas, Channels, Statistics, MetadataIndexes, ChunkIndexes and
//    SummaryOffsets, grouped by opcode, and the Footer. Each chunk's records are compressed by
//    zstd or not at all, and decompress to the chunk's uncompressed_size. The chunks' (of their
//    uncompressed records), the data section's and the summary's CRCs are computed here again
//    (a CRC-32 of this file's own).
// 2. McapIndexedReader reads the summary (its CRC checked): the Statistics must count what the
//    stream held, every ChunkIndex and SummaryOffset must point at its records, the metadata
//    must hold the run's configuration, and readMessages over everything must give the
//    stream's messages, each once.
// 3. Every message is UTF-8 JSON that its channel's JSON Schema ("jsonschema") accepts (a string
//    of contentMediaType image/png: base64 of a PNG, by its signature, or ""; a string of an
//    enum: one of its values), and a channel message's field that names an image topic (an enum
//    of a topic's name) has a message on that topic at its log time.
//
// Prints one JSON line per message, in file order: topic, schema, channel_id, sequence,
// log_time, publish_time (integers, exact) and the message as it is in the file (its JSON,
// integers exact), or with --digest its SHA-256 instead; then a line of totals. Exits 1 on the
// first check that fails, naming it.
import { createHash } from "node:crypto";
import { readFileSync } from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress as unzstd } from "fzstd";

const [file, ...flags] = process.argv.slice(2);
if (!file || flags.some((f) => f !== "--digest")) {
  console.error("usage: node check.mjs FILE.mcap [--digest]");
  process.exit(2);
}
const digestOnly = flags.includes("--digest");
const bytes = readFileSync(file);

function check(ok, what) {
  if (!ok) throw new Error(what);
}

// ---- CRC-32 (ISO-HDLC, zlib's), written here ---------------------------------------------
const crcTable = new Uint32Array(256).map((_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32(data) {
  let c = 0xffffffff;
  for (let i = 0; i < data.length; i++) c = crcTable[(c ^ data[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

// ---- the chunks' compressions: zstd (decoded by fzstd) and none -----------------------------
const decompressHandlers = {
  zstd: (data, size) => {
    const out = unzstd(data);
    check(BigInt(out.length) === size, `a zstd chunk of ${out.length} bytes, its uncompressed_size ${size}`);
    return out;
  },
};
function recordsOf(chunk) {
  check(chunk.compression === "" || chunk.compression in decompressHandlers,
        `chunk compression "${chunk.compression}" (the export writes zstd or none)`);
  return chunk.compression === "" ? chunk.records : decompressHandlers[chunk.compression](chunk.records, chunk.uncompressedSize);
}

// ---- the records, as this file lays them out (opcode, uint64 length) ----------------------
const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
const u64 = (at) => view.getBigUint64(at, true);
function recordAt(at) {
  const length = Number(u64(at + 1));
  return { op: bytes[at], at, end: at + 9 + length, content: at + 9 };
}
// The records of a chunk's (uncompressed) records field: offset -> [opcode, channel id, log time].
function chunkRecords(records) {
  const v = new DataView(records.buffer, records.byteOffset, records.byteLength);
  const out = new Map();
  for (let at = 0; at < records.length; ) {
    const op = records[at];
    const length = Number(v.getBigUint64(at + 1, true));
    out.set(at, op === 5 ? [op, v.getUint16(at + 9, true), v.getBigUint64(at + 15, true)] : [op]);
    at += 9 + length;
    check(at <= records.length, "a record in a chunk runs past the chunk");
  }
  return out;
}

// ---- 1. the stream, record by record -------------------------------------------------------
const DATA = new Set(["Schema", "Channel", "Message", "Chunk", "MessageIndex", "Metadata", "DataEnd"]);
const SUMMARY = ["Schema", "Channel", "Statistics", "MetadataIndex", "ChunkIndex", "AttachmentIndex", "SummaryOffset"];
function readStream() {
  const reader = new McapStreamReader({ validateCrcs: true, includeChunks: true, decompressHandlers });
  reader.append(bytes);
  const s = { schemas: new Map(), channels: new Map(), messages: [], chunks: [], metadata: [], summary: [] };
  let inChunk = 0; // records of the open chunk still to come
  let chunk; // the open chunk: its records by offset, the messages not yet indexed
  let section = "start";
  for (let r; (r = reader.nextRecord()); ) {
    if (section === "start") {
      check(r.type === "Header", `the first record is ${r.type}, not the Header`);
      check(r.profile === "" && r.library.startsWith("afford "), `Header: profile "${r.profile}", library "${r.library}"`);
      section = "data";
      continue;
    }
    if (section === "data") {
      check(DATA.has(r.type), `${r.type} record in the data section`);
      if (inChunk > 0) {
        check(["Schema", "Channel", "Message"].includes(r.type), `${r.type} inside a chunk`);
        inChunk--;
      } else {
        check(r.type !== "Message", "a Message outside a chunk");
      }
      if (r.type === "Chunk") {
        check(chunk === undefined || chunk.unindexed.size === 0, "a chunk's messages are not all indexed");
        const uncompressed = recordsOf(r);
        check(crc32(uncompressed) === r.uncompressedCrc, "chunk CRC");
        check(BigInt(uncompressed.length) === r.uncompressedSize, "chunk uncompressed_size");
        const records = chunkRecords(uncompressed);
        chunk = { records, unindexed: new Set([...records].filter(([, rec]) => rec[0] === 5).map(([at]) => at)) };
        inChunk = records.size;
        s.chunks.push({ start: r.messageStartTime, end: r.messageEndTime, messages: chunk.unindexed.size,
                        compression: r.compression, compressed: BigInt(r.records.length), uncompressed: r.uncompressedSize });
      } else if (r.type === "MessageIndex") {
        check(chunk !== undefined && inChunk === 0, "a MessageIndex not after a chunk");
        for (const [logTime, offset] of r.records) {
          const rec = chunk.records.get(Number(offset));
          check(rec && rec[0] === 5 && rec[1] === r.channelId && rec[2] === logTime,
                `MessageIndex of channel ${r.channelId}: offset ${offset} is not its message of time ${logTime}`);
          check(chunk.unindexed.delete(Number(offset)), `a message indexed twice (offset ${offset})`);
        }
      } else if (r.type === "Schema") {
        s.schemas.set(r.id, r);
      } else if (r.type === "Channel") {
        check(s.schemas.has(r.schemaId), `channel ${r.id} before its schema ${r.schemaId}`);
        s.channels.set(r.id, r);
      } else if (r.type === "Message") {
        s.messages.push(r);
      } else if (r.type === "Metadata") {
        s.metadata.push(r);
      } else if (r.type === "DataEnd") {
        check(chunk === undefined || chunk.unindexed.size === 0, "the last chunk's messages are not all indexed");
        s.dataEndCrc = r.dataSectionCrc;
        section = "summary";
      }
      continue;
    }
    if (r.type === "Footer") {
      s.footer = r;
      break;
    }
    check(SUMMARY.includes(r.type), `${r.type} record in the summary section`);
    const last = s.summary.at(-1);
    check(r.type === last || !s.summary.includes(r.type), `summary records not grouped by opcode: ${r.type} again`);
    s.summary.push(r.type);
    if (r.type === "Statistics") s.statistics = r;
  }
  check(reader.done(), "the stream did not end with the Footer and the magic");
  check(s.footer !== undefined, "no Footer");
  return s;
}

// The data section's CRC (every byte before DataEnd) and the summary's (from the summary up to the Footer's CRC).
function checkFileCrcs(s) {
  const summaryStart = Number(s.footer.summaryStart);
  const dataEnd = summaryStart - 13;
  check(recordAt(dataEnd).op === 0x0f, "no DataEnd right before the summary");
  check(crc32(bytes.subarray(0, dataEnd)) === s.dataEndCrc, "data section CRC");
  const footerAt = bytes.length - 8 - 29;
  check(recordAt(footerAt).op === 0x02, "no Footer before the magic");
  check(crc32(bytes.subarray(summaryStart, footerAt + 25)) === s.footer.summaryCrc, "summary CRC");
}

// ---- 2. the summary and the index ------------------------------------------------------------
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};

function checkSummary(s, indexed) {
  const st = indexed.statistics;
  check(st !== undefined, "no Statistics");
  const counts = new Map();
  for (const m of s.messages) counts.set(m.channelId, (counts.get(m.channelId) ?? 0n) + 1n);
  check(st.messageCount === BigInt(s.messages.length), `Statistics: ${st.messageCount} messages, the file ${s.messages.length}`);
  check(st.chunkCount === s.chunks.length, `Statistics: ${st.chunkCount} chunks, the file ${s.chunks.length}`);
  check(st.channelCount === s.channels.size && st.schemaCount === s.schemas.size, "Statistics: channels or schemas");
  check(st.metadataCount === s.metadata.length && st.attachmentCount === 0, "Statistics: metadata or attachments");
  for (const id of s.channels.keys())
    check((st.channelMessageCounts.get(id) ?? 0n) === (counts.get(id) ?? 0n), `Statistics: channel ${id}'s count`);
  check([...st.channelMessageCounts.keys()].every((id) => s.channels.has(id)), "Statistics: a count of no channel");
  const times = s.messages.map((m) => m.logTime);
  if (times.length) {
    const min = times.reduce((a, b) => (b < a ? b : a)), max = times.reduce((a, b) => (b > a ? b : a));
    check(st.messageStartTime === min && st.messageEndTime === max, "Statistics: message start or end time");
  }
  for (const [id, c] of s.channels) {
    const d = indexed.channelsById.get(id);
    check(d && d.topic === c.topic && d.schemaId === c.schemaId && d.messageEncoding === c.messageEncoding,
          `summary Channel ${id}`);
    check(c.messageEncoding === "json", `channel ${c.topic}: message encoding ${c.messageEncoding}`);
  }
  for (const [id, sc] of s.schemas) {
    const d = indexed.schemasById.get(id);
    check(d && d.name === sc.name && d.encoding === "jsonschema" && Buffer.compare(d.data, sc.data) === 0,
          `summary Schema ${id}`);
  }
  check(indexed.chunkIndexes.length === s.chunks.length, "a ChunkIndex per chunk");
  indexed.chunkIndexes.forEach((ci, i) => {
    const r = recordAt(Number(ci.chunkStartOffset));
    check(r.op === 0x06 && BigInt(r.end - r.at) === ci.chunkLength, `ChunkIndex ${i}: no chunk of its length there`);
    check(ci.messageStartTime === s.chunks[i].start && ci.messageEndTime === s.chunks[i].end, `ChunkIndex ${i}: times`);
    check(ci.compression === s.chunks[i].compression && ci.compressedSize === s.chunks[i].compressed &&
          ci.uncompressedSize === s.chunks[i].uncompressed, `ChunkIndex ${i}: compression or sizes`);
    let indexBytes = 0;
    for (const [channel, at] of ci.messageIndexOffsets) {
      const m = recordAt(Number(at));
      check(m.op === 0x07 && view.getUint16(m.content, true) === channel, `ChunkIndex ${i}: channel ${channel}'s index`);
      indexBytes += m.end - m.at;
    }
    check(BigInt(indexBytes) === ci.messageIndexLength, `ChunkIndex ${i}: message_index_length`);
  });
  const ops = { 3: "Schema", 4: "Channel", 11: "Statistics", 13: "MetadataIndex", 8: "ChunkIndex" };
  check(indexed.summaryOffsetsByOpcode.size === new Set(s.summary.filter((t) => t !== "SummaryOffset")).size,
        "a SummaryOffset per group of the summary");
  for (const [op, so] of indexed.summaryOffsetsByOpcode) {
    const end = Number(so.groupStart + so.groupLength);
    let n = 0;
    for (let at = Number(so.groupStart); at < end; at = recordAt(at).end, n++)
      check(bytes[at] === op, `SummaryOffset of ${ops[op] ?? op}: a record of opcode ${bytes[at]} in its group`);
    check(n === s.summary.filter((t) => t === ops[op]).length, `SummaryOffset of ${ops[op] ?? op}: its group's records`);
  }
}

async function checkIndexed(s) {
  const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  checkSummary(s, indexed);
  const metadata = [];
  for await (const m of indexed.readMetadata()) metadata.push(m);
  check(metadata.length === 1 && metadata[0].name === "afford", "one Metadata record, \"afford\"");
  const meta = metadata[0].metadata;
  check(meta.get("config_yaml")?.length > 0 && meta.get("afford_version")?.length > 0 && meta.get("run_id") !== undefined,
        "the metadata's config_yaml, afford_version and run_id");
  // readMessages over everything gives the stream's messages, each once.
  const key = (m) => `${m.channelId}/${m.sequence}`;
  const byKey = new Map(s.messages.map((m) => [key(m), m]));
  check(byKey.size === s.messages.length, "two messages of one channel with the same sequence");
  let n = 0, last = -1n;
  for await (const m of indexed.readMessages({ validateCrcs: true })) {
    const want = byKey.get(key(m));
    check(want !== undefined, `readMessages: a message (channel ${m.channelId}, sequence ${m.sequence}) the stream lacks`);
    check(want.logTime === m.logTime && want.publishTime === m.publishTime && Buffer.compare(want.data, m.data) === 0,
          `readMessages: channel ${m.channelId} sequence ${m.sequence} differs from the stream's`);
    byKey.delete(key(m));
    check(m.logTime >= last, "readMessages: not in log time order");
    last = m.logTime;
    n++;
  }
  check(n === s.messages.length && byKey.size === 0, `readMessages gave ${n} messages, the stream ${s.messages.length}`);
  return { library: indexed.header.library, run_id: meta.get("run_id"), afford_version: meta.get("afford_version") };
}

// ---- 3. each message against its JSON Schema (the keywords the export's schemas use) -------------
const BASE64 = /^(?:[A-Za-z0-9+/]{4})*(?:[A-Za-z0-9+/]{2}==|[A-Za-z0-9+/]{3}=)?$/;
const KNOWN = new Set(["$schema", "title", "description", "type", "properties", "required", "additionalProperties",
  "items", "minItems", "maxItems", "minimum", "maximum", "contentEncoding", "contentMediaType", "enum"]);
const PNG_SIGNATURE = Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);
function validate(schema, v, path, references) {
  for (const k of Object.keys(schema)) check(KNOWN.has(k), `${path}: schema keyword ${k} this checker does not know`);
  const types = { object: () => v !== null && typeof v === "object" && !Array.isArray(v), array: () => Array.isArray(v),
    string: () => typeof v === "string", number: () => typeof v === "number", boolean: () => typeof v === "boolean",
    integer: () => Number.isInteger(v) };
  check(types[schema.type]?.(), `${path}: ${JSON.stringify(v)?.slice(0, 40)} is not of type ${schema.type}`);
  if (schema.minimum !== undefined) check(v >= schema.minimum, `${path}: below ${schema.minimum}`);
  if (schema.maximum !== undefined) check(v <= schema.maximum, `${path}: above ${schema.maximum}`);
  if (schema.contentEncoding === "base64") check(BASE64.test(v), `${path}: not base64`);
  if (schema.enum !== undefined) {  // (the export's: an image topic's name, or "")
    check(schema.enum.includes(v), `${path}: ${JSON.stringify(v)?.slice(0, 40)} is not one of ${schema.enum}`);
    if (v !== "") references.push([v, path]);
  }
  if (schema.contentMediaType !== undefined) {  // an image: none ("") or a PNG
    check(schema.contentMediaType === "image/png" && schema.contentEncoding === "base64",
      `${path}: contentMediaType ${schema.contentMediaType} this checker does not know`);
    check(v === "" || Buffer.from(v, "base64").subarray(0, 8).equals(PNG_SIGNATURE), `${path}: not a PNG`);
  }
  if (schema.type === "array") {
    if (schema.minItems !== undefined) check(v.length >= schema.minItems, `${path}: fewer than ${schema.minItems}`);
    if (schema.maxItems !== undefined) check(v.length <= schema.maxItems, `${path}: more than ${schema.maxItems}`);
    v.forEach((e, i) => validate(schema.items, e, `${path}[${i}]`, references));
  }
  if (schema.type === "object") {
    for (const r of schema.required ?? []) check(r in v, `${path}: no ${r}`);
    for (const [k, e] of Object.entries(v)) {
      if (schema.properties?.[k]) validate(schema.properties[k], e, `${path}.${k}`, references);
      else check(schema.additionalProperties !== false, `${path}: ${k} is not in the schema`);
    }
  }
}

// ---- the run ------------------------------------------------------------------------------------
try {
  const s = readStream();
  checkFileCrcs(s);
  const info = await checkIndexed(s);
  const utf8 = new TextDecoder("utf-8", { fatal: true });
  const schemas = new Map([...s.schemas].map(([id, sc]) => [id, JSON.parse(utf8.decode(sc.data))]));
  const perTopic = {};
  const out = [];
  const at = new Set(s.messages.map((m) => `${s.channels.get(m.channelId).topic}@${m.logTime}`));
  for (const m of s.messages) {
    const c = s.channels.get(m.channelId);
    const schema = s.schemas.get(c.schemaId);
    const text = utf8.decode(m.data);
    const references = [];  // [topic, field]: the field's pixels are on the topic at the message's time
    validate(schemas.get(c.schemaId), JSON.parse(text), `${c.topic}#${m.sequence}`, references);
    for (const [topic, path] of references)
      check(topic.startsWith("/") && at.has(`${topic}@${m.logTime}`), `${path}: no message on ${topic} at its time`);
    perTopic[c.topic] = (perTopic[c.topic] ?? 0) + 1;
    const body = digestOnly ? `"sha256":"${createHash("sha256").update(m.data).digest("hex")}"`
                            : `"message":${/[\n\r]/.test(text) ? JSON.stringify(JSON.parse(text)) : text}`;
    out.push(`{"topic":${JSON.stringify(c.topic)},"schema":${JSON.stringify(schema.name)},"channel_id":${m.channelId},` +
             `"sequence":${m.sequence},"log_time":${m.logTime},"publish_time":${m.publishTime},${body}}`);
    if (out.length >= 4096) process.stdout.write(out.splice(0).join("\n") + "\n");
  }
  if (out.length) process.stdout.write(out.join("\n") + "\n");
  const totals = { file, bytes: bytes.length, messages: s.messages.length, chunks: s.chunks.length,
    compression: [...new Set(s.chunks.map((c) => c.compression))].join(","),
    record_bytes: Number(s.chunks.reduce((n, c) => n + c.uncompressed, 0n)),
    schemas: s.schemas.size, channels: s.channels.size, per_topic: perTopic, ...info, ok: true };
  process.stdout.write(JSON.stringify({ totals }) + "\n");
} catch (e) {
  console.error(`mcapcheck: ${file}: ${e.message}`);
  process.exit(1);
}
