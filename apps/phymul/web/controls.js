// The panel's live controls, built from the scene: a slider per obstacle (along its slide
// direction), a field per pressure load and per volume constraint.
function heading(parent, text) {
  const h = document.createElement('h2');
  h.textContent = text;
  parent.append(h);
}

function throttled(send, ms) {
  let last = 0, timer = null, pending = null;
  return (message) => {
    pending = message;
    const wait = last + ms - performance.now();
    if (wait <= 0) { last = performance.now(); send(pending); return; }
    clearTimeout(timer);
    timer = setTimeout(() => { last = performance.now(); send(pending); }, wait);
  };
}

export function buildControls(scene, connection, places) {
  places.obstacles.textContent = '';
  places.loads.textContent = '';
  const sliders = [];
  if (scene.obstacles.length) heading(places.obstacles, 'Obstacles');
  const send = throttled((m) => connection.send(m), 33);
  scene.obstacles.forEach((o) => {
    const label = document.createElement('label');
    const value = document.createElement('span');
    const slider = document.createElement('input');
    Object.assign(slider, { type: 'range', min: o.slide.min, max: o.slide.max, step: (o.slide.max - o.slide.min) / 400, value: 0 });
    slider.dataset.obstacle = o.name;
    slider.oninput = () => {
      value.textContent = `${(slider.value * 1e3).toFixed(1)} mm`;
      send({ op: 'move_obstacle', obstacle: o.name, offset: Number(slider.value) });
    };
    label.append(`${o.name} `, value, slider);
    places.obstacles.append(label);
    sliders.push({ slider, value, direction: o.slide.direction });
  });

  const field = (text, unit, initial, onset) => {
    const label = document.createElement('label');
    const input = document.createElement('input');
    Object.assign(input, { type: 'number', value: initial, step: 'any' });
    input.onchange = () => onset(Number(input.value));
    label.append(`${text} `, input, ` ${unit}`);
    places.loads.append(label);
    return input;
  };
  heading(places.loads, 'Loads');
  const pressures = scene.pressures.map((p, k) =>
    field(`${p.name} pressure`, 'kPa', 0, (v) => connection.send({ op: 'set_pressure', load: k, value: v * 1e3 })));
  const volumes = scene.volumes.map((v, k) =>
    field(`${v.name} volume`, 'mL', (v.rest * 1e6).toFixed(1),
      (x) => connection.send({ op: 'set_target_volume', object: k, value: x * 1e-6 })));

  // A constant force on one node (the last one dragged, or any id): a load changed live.
  const label = document.createElement('label');
  const node = Object.assign(document.createElement('input'), { type: 'number', min: 0, max: scene.nodes - 1, step: 1, value: 0 });
  const force = [0, 0, 0].map(() => Object.assign(document.createElement('input'), { type: 'number', step: 'any', value: 0 }));
  node.style.width = '52px';
  force.forEach((f) => { f.style.width = '44px'; });
  const apply = Object.assign(document.createElement('button'), { textContent: 'apply' });
  apply.onclick = () => connection.send({ op: 'set_force', node: Number(node.value), force: force.map((f) => Number(f.value)) });
  label.append('force on node ', node, ' N ', ...force, apply);
  places.loads.append(label);

  // Status: fields and sliders follow the run unless the user is changing them.
  return {
    picked(id) { node.value = id; },
    status(m) {
      sliders.forEach((s, k) => {
        const t = m.obstacles[k].translation;
        const offset = t[0] * s.direction[0] + t[1] * s.direction[1] + t[2] * s.direction[2];
        s.value.textContent = `${(offset * 1e3).toFixed(1)} mm`;
        if (document.activeElement !== s.slider) s.slider.value = offset;
      });
      pressures.forEach((input, k) => {
        if (document.activeElement !== input) input.value = (m.pressures[k] * 1e-3).toPrecision(4);
      });
      volumes.forEach((input, k) => {
        if (document.activeElement !== input) input.value = (m.target_volumes[k] * 1e6).toPrecision(4);
      });
    },
  };
}
