// A Foxglove client of the older vintage: @foxglove/ws-protocol 0.8.0's FoxgloveClient over `ws`,
// offering only its own subprotocol (foxglove.websocket.v1). It connects to the live view, waits
// for the channel of TOPIC, subscribes and decodes COUNT messages as nav_msgs/Odometry CDR with
// @foxglove/cdr's reader (the first COUNT stamped AFTER_S or later); prints one JSON line: the negotiated subprotocol, the channel and the
// decoded messages. Driven by tests/ros/test_foxglove_older_client.py (which sets NODE_PATH to
// the live view's web/node_modules). Usage: node foxglove_older_client.js URL TOPIC COUNT AFTER_S
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { CdrReader } = require("@foxglove/cdr");
const WebSocket = require("ws");

const [url, topic, count, afterS] = [process.argv[2], process.argv[3], Number(process.argv[4] || 1),
                                     Number(process.argv[5] || 0)];
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const out = { offered: FoxgloveClient.SUPPORTED_SUBPROTOCOL, protocol: null, channel: null, messages: [] };
let subscription = null;

function vector(reader, n) {
  return Array.from({ length: n }, () => reader.float64());
}

// nav_msgs/Odometry in field order (ROS 2 .msg definitions; CDR alignment is the reader's)
function decodeOdometry(data) {
  const r = new CdrReader(data);
  const stamp = { sec: r.int32(), nanosec: r.uint32() };
  const frame_id = r.string();
  const child_frame_id = r.string();
  const position = vector(r, 3);
  const orientation = vector(r, 4);
  r.float64Array(36);
  const linear = vector(r, 3);
  const angular = vector(r, 3);
  r.float64Array(36);
  return { stamp, frame_id, child_frame_id, position, orientation, linear, angular,
           consumed: r.decodedBytes, length: data.byteLength };
}

const timer = setTimeout(() => {
  out.error = `timed out: ${out.messages.length} of ${count} messages`;
  finish(1);
}, 60000);

function finish(code) {
  clearTimeout(timer);
  process.stdout.write(JSON.stringify(out) + "\n");
  try { client.close(); } catch (e) { /* closing is a courtesy */ }
  process.exit(code);
}

ws.on("open", () => { out.protocol = ws.protocol; });
ws.on("unexpected-response", (req, res) => {
  out.error = `HTTP ${res.statusCode}`;
  finish(1);
});
client.on("error", (err) => { out.error = String(err && err.message || err); finish(1); });
client.on("advertise", (channels) => {
  const channel = channels.find((c) => c.topic === topic);
  if (channel && subscription === null) {
    out.channel = { topic: channel.topic, encoding: channel.encoding, schemaName: channel.schemaName,
                    schemaEncoding: channel.schemaEncoding };
    subscription = client.subscribe(channel.id);
  }
});
client.on("message", (event) => {
  if (event.subscriptionId !== subscription) {
    return;
  }
  const msg = decodeOdometry(event.data);
  if (msg.stamp.sec < afterS) {
    return;
  }
  msg.log_time_ns = event.timestamp.toString();
  out.messages.push(msg);
  if (out.messages.length >= count) {
    finish(0);
  }
});
