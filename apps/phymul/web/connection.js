// The WebSocket to phymul serve (docs/live-view.md): JSON text both ways, binary frames from
// the server. Reconnects after a lost connection; requests with an id resolve on their reply.
export class Connection {
  constructor(handlers) {
    this.handlers = handlers;
    this.nextId = 1;
    this.waiting = new Map();
    this.open();
  }

  url() {
    const token = new URLSearchParams(location.search).get('token');
    return `ws://${location.host}/ws${token ? '?token=' + encodeURIComponent(token) : ''}`;
  }

  open() {
    const ws = new WebSocket(this.url());
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => this.handlers.status('connected');
    ws.onclose = (e) => {
      this.handlers.status(`disconnected (${e.code}${e.reason ? ': ' + e.reason : ''}); retrying`);
      setTimeout(() => this.open(), 2000);
    };
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return this.handlers.binary(e.data);
      const m = JSON.parse(e.data);
      if (m.id !== undefined && this.waiting.has(m.id)) {
        this.waiting.get(m.id)(m);
        this.waiting.delete(m.id);
      }
      this.handlers.message(m);
    };
    this.ws = ws;
  }

  send(message) {
    if (this.ws.readyState === WebSocket.OPEN) this.ws.send(JSON.stringify(message));
  }

  // Resolves with the server's reply (state, ok or error).
  request(message) {
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.waiting.set(id, resolve);
      this.send({ ...message, id });
    });
  }
}

// Binary messages: the triangles once, then frames (little-endian).
export function decodeBinary(buffer) {
  const head = new Uint32Array(buffer, 0, 2);
  if (head[0] === 1) {
    const [, nodes, triangles] = new Uint32Array(buffer, 0, 3);
    return {
      kind: 'mesh',
      nodes,
      indices: new Uint32Array(buffer, 12, 3 * triangles),
      rest: new Float32Array(buffer, 12 + 12 * triangles, 3 * nodes),
    };
  }
  const time = new Float64Array(buffer, 8, 1)[0];
  const [nodes, obstacles] = new Uint32Array(buffer, 16, 2);
  return {
    kind: 'frame',
    sequence: head[1],
    time,
    positions: new Float32Array(buffer, 24, 3 * nodes),
    displacement: new Float32Array(buffer, 24 + 12 * nodes, nodes),
    obstacles: new Float32Array(buffer, 24 + 16 * nodes, 3 * obstacles),
  };
}
