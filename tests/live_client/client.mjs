// A Foxglove WebSocket client (npm's @foxglove/ws-protocol, not shc's code): subscribes the given topics of a live
// shc run, decodes each message with its advertised ROS 1 definition (@foxglove/rosmsg-serialization) and prints one
// JSON line per message: {"topic", "logTime", "message"}. Ends when the server closes or after SECONDS.
// Usage: node client.mjs URL SECONDS TOPIC...
import wsProtocol from "@foxglove/ws-protocol";
import rosmsg from "@foxglove/rosmsg";
import serialization from "@foxglove/rosmsg-serialization";
import WebSocket from "ws";

const [url, seconds, ...topics] = process.argv.slice(2);
const { FoxgloveClient } = wsProtocol;
const { parse } = rosmsg;
const { MessageReader } = serialization;
const ws = new WebSocket(url, ["foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const readers = new Map();
const names = new Map();
client.on("advertise", (channels) => {
  for (const channel of channels) {
    if (!topics.includes(channel.topic)) continue;
    const id = client.subscribe(channel.id);
    readers.set(id, new MessageReader(parse(channel.schema, { ros2: false })));
    names.set(id, channel.topic);
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const reader = readers.get(subscriptionId);
  if (!reader) return;
  const message = reader.readMessage(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
  process.stdout.write(JSON.stringify({ topic: names.get(subscriptionId), logTime: String(timestamp), message },
    (key, value) => (typeof value === "bigint" ? String(value) : ArrayBuffer.isView(value) ? Array.from(value) : value)) + "\n");
});
client.on("error", (error) => process.stderr.write(`error: ${error}\n`));
client.on("close", () => process.exit(0));
setTimeout(() => process.exit(0), Number(seconds) * 1000);
