// Displacement colours: a perceptually even map (viridis, five stops) and its legend.
const STOPS = [
  [0.267, 0.005, 0.329],
  [0.229, 0.322, 0.546],
  [0.128, 0.567, 0.551],
  [0.369, 0.789, 0.383],
  [0.993, 0.906, 0.144],
];

export function colourAt(s, out, at) {
  const x = Math.min(Math.max(s, 0), 1) * (STOPS.length - 1);
  const k = Math.min(Math.floor(x), STOPS.length - 2);
  const f = x - k;
  for (let c = 0; c < 3; ++c) out[at + c] = STOPS[k][c] * (1 - f) + STOPS[k + 1][c] * f;
}

export function drawLegend(canvas) {
  const g = canvas.getContext('2d');
  const rgb = [0, 0, 0];
  for (let y = 0; y < canvas.height; ++y) {
    colourAt(1 - y / (canvas.height - 1), rgb, 0);
    g.fillStyle = `rgb(${rgb.map((v) => Math.round(255 * v)).join(',')})`;
    g.fillRect(0, y, canvas.width, 1);
  }
}
