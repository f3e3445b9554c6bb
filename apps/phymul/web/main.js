// phymul serve's page: the view, the controls panel and the monitor plot, wired to the
// server. window.phymul exposes the page's state to the browser tests.
import { Connection, decodeBinary } from './connection.js';
import { drawLegend } from './colours.js';
import { MonitorPlot } from './plot.js';
import { View } from './view.js';
import { buildControls } from './controls.js';

const $ = (id) => document.getElementById(id);
const view = new View($('view'));
const plot = new MonitorPlot($('plot'), $('monitor-choice'));
const page = { frames: 0, time: 0, status: null, scene: null, error: '', drag: null };
let controls = null;

const connection = new Connection({
  status: (text) => { $('connection').textContent = text; },
  message: (m) => {
    if (m.type === 'scene') page.scene = m;
    if (m.type === 'status') {
      page.status = m;
      $('rtf').textContent = m.paused ? 'paused' : m.real_time_factor.toFixed(2);
      $('message').textContent = m.error ? `stopped: ${m.error}` : '';
      plot.add(m.time, m.monitors);
      if (controls) controls.status(m);
    }
    if (m.type === 'error') {
      page.error = m.message;
      $('message').textContent = m.message;
    }
  },
  binary: (buffer) => {
    const b = decodeBinary(buffer);
    if (b.kind === 'mesh' && page.scene) {
      view.build(page.scene, b);
      plot.setNames(page.scene.monitors);
      controls = buildControls(page.scene, connection, { obstacles: $('obstacles'), loads: $('loads') });
    } else if (b.kind === 'frame') {
      view.update(b);
      page.frames += 1;
      page.time = b.time;
      $('time').textContent = b.time.toFixed(3);
      $('legend-max').textContent = `${(view.displacementScale * 1e3).toPrecision(3)} mm`;
    }
  },
});

for (const op of ['play', 'pause', 'reset']) $(op).onclick = () => connection.send({ op });
$('step').onclick = () => connection.send({ op: 'step', n: 1 });
$('pace').onchange = (e) => connection.send({ op: 'pace', value: e.target.value });
drawLegend($('legend-bar'));

// Dragging a node: a spring from it to the pointer, in the plane facing the camera.
const canvas = $('view');
let lastSent = 0;
canvas.addEventListener('pointerdown', (e) => {
  const hit = view.pick(e.clientX, e.clientY);
  if (!hit) return;
  view.controls.enabled = false;
  canvas.setPointerCapture(e.pointerId);
  page.drag = { node: hit.node, through: hit.point, target: hit.point.toArray() };
  if (controls) controls.picked(hit.node);
  connection.send({ op: 'drag', node: hit.node, target: page.drag.target });
});
canvas.addEventListener('pointermove', (e) => {
  if (!page.drag) return;
  const p = view.pointOnPlane(e.clientX, e.clientY, page.drag.through);
  if (!p) return;
  const pull = p.clone().sub(page.drag.through);
  const most = 0.5 * page.scene.size;  // the server refuses targets beyond the scene's size
  if (pull.length() > most) pull.setLength(most);
  page.drag.target = page.drag.through.clone().add(pull).toArray();
  const now = performance.now();
  if (now - lastSent > 30) {
    lastSent = now;
    connection.send({ op: 'drag', node: page.drag.node, target: page.drag.target });
  }
});
const release = () => {
  if (!page.drag) return;
  connection.send({ op: 'drag', node: page.drag.node, target: page.drag.target });
  connection.send({ op: 'release' });
  page.drag = null;
  view.controls.enabled = true;
};
canvas.addEventListener('pointerup', release);
canvas.addEventListener('pointercancel', release);

function animate() {
  requestAnimationFrame(animate);
  view.render();
}
animate();

window.phymul = {
  page,
  screenOf: (node) => view.screenOf(node),
  setMeshVisible: (visible) => { view.mesh.visible = visible; view.render(); },
  state: (node) => connection.request(node === undefined ? { op: 'state' } : { op: 'state', node }),
  send: (message) => connection.request(message),
};
