// The live plot of the chosen monitors over simulated time (the last 60 s of samples).
const COLOURS = ['#4fc3f7', '#ffb74d', '#81c784', '#e57373', '#ba68c8', '#fff176'];
const KEEP = 600;

export class MonitorPlot {
  constructor(canvas, choice) {
    this.canvas = canvas;
    this.choice = choice;
    this.series = new Map();  // name -> {t: [], v: [], box}
  }

  setNames(names) {
    this.choice.textContent = '';
    this.series.clear();
    names.forEach((name, k) => {
      const label = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.checked = / force /.test(name) || (k === 0 && !names.some((n) => / force /.test(n)));
      label.append(box, ' ', name);
      label.style.color = COLOURS[k % COLOURS.length];
      this.choice.append(label);
      this.series.set(name, { t: [], v: [], box, colour: COLOURS[k % COLOURS.length] });
    });
  }

  add(time, monitors) {
    for (const [name, s] of this.series) {
      if (s.t.length && time < s.t[s.t.length - 1]) { s.t.length = 0; s.v.length = 0; }  // reset
      s.t.push(time);
      s.v.push(monitors[name]);
      if (s.t.length > KEEP) { s.t.shift(); s.v.shift(); }
    }
    this.draw();
  }

  draw() {
    const g = this.canvas.getContext('2d');
    const w = this.canvas.width, h = this.canvas.height, pad = 28;
    g.clearRect(0, 0, w, h);
    const shown = [...this.series.values()].filter((s) => s.box.checked && s.t.length > 1);
    if (!shown.length) return;
    const t0 = Math.min(...shown.map((s) => s.t[0])), t1 = Math.max(...shown.map((s) => s.t[s.t.length - 1]));
    let lo = Math.min(...shown.map((s) => Math.min(...s.v))), hi = Math.max(...shown.map((s) => Math.max(...s.v)));
    // At least 1 % of the values' size: a steady monitor draws flat, not as magnified noise.
    const least = Math.max(0.01 * Math.max(Math.abs(hi), Math.abs(lo)), 1e-12);
    if (hi - lo < least) { const mid = (hi + lo) / 2; hi = mid + least / 2; lo = mid - least / 2; }
    const x = (t) => pad + (w - pad - 4) * (t - t0) / Math.max(t1 - t0, 1e-9);
    const y = (v) => h - 14 - (h - 22) * (v - lo) / (hi - lo);
    g.fillStyle = '#aaa';
    g.font = '10px sans-serif';
    g.fillText(hi.toPrecision(3), 2, 10);
    g.fillText(lo.toPrecision(3), 2, h - 14);
    g.fillText(`${t0.toFixed(2)} s`, pad, h - 2);
    g.fillText(`${t1.toFixed(2)} s`, w - 40, h - 2);
    for (const s of shown) {
      g.strokeStyle = s.colour;
      g.beginPath();
      s.t.forEach((t, k) => (k ? g.lineTo(x(t), y(s.v[k])) : g.moveTo(x(t), y(s.v[k]))));
      g.stroke();
    }
  }
}
