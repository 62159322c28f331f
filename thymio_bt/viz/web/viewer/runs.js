/* A run's data as the viewer reads it (class Run), the viewer's state and the page's frame. */
/* ------------------------------------------------------------------ a run's data */

class Run {
  constructor(d, index) {
    this.d = d;
    this.index = index;
    this.letter = String.fromCharCode(65 + index);
    this.paths = d.tree.map((row) => row[0]);
    this.nodeIndex = new Map(this.paths.map((p, i) => [p, i]));
    this.changes = d.status.map(([gaps, letters]) => {
      let at = 0;
      return { at: gaps.map((g) => (at += g)), letters: letters.split("") };
    });
    this.events = (d.events || []).slice();
    this.bbIndex = new Map();
    this.pathD = "";
    this.pathEnds = [];
    for (let i = 0; i < d.t.length; i++) this.extendPath(i);
  }

  get n() {
    return this.d.t.length;
  }

  extendPath(i) {
    const d = this.d;
    if (d.x[i] === null) {
      this.pathEnds.push(this.pathD.length);
      return;
    }
    let prev = i - 1;
    while (prev >= 0 && d.x[prev] === null) prev -= 1;
    const jump = prev !== i - 1 || prev < 0 || Math.hypot(d.x[i] - d.x[prev], d.y[i] - d.y[prev]) > 0.05;
    this.pathD += (jump ? "M" : "L") + d.x[i] + " " + -d.y[i] + " ";
    this.pathEnds.push(this.pathD.length);
  }

  /** The index of the sample shown at time t: the last at or before it (the first before any). */
  indexAt(t) {
    return this.n ? Math.max(0, lastAtOrBefore(this.d.t, t + EPS)) : -1;
  }

  status(node, i) {
    const c = this.changes[node];
    const at = lastAtOrBefore(c.at, i);
    return at < 0 ? "-" : c.letters[at];
  }

  /** The blackboard change of key in effect at index i ([index, value]), or undefined. */
  bbAt(key, i) {
    const changes = this.d.bb[key];
    let at = this.bbIndex.get(key);
    if (!at || at.length !== changes.length) {
      at = changes.map((c) => c[0]);
      this.bbIndex.set(key, at);
    }
    const k = lastAtOrBefore(at, i);
    return k < 0 ? undefined : changes[k];
  }

  pose(i) {
    const d = this.d;
    return i < 0 || d.x[i] === null ? null : { x: d.x[i], y: d.y[i], yaw: d.yaw[i] };
  }

  /** Append one tick record of the log's format (a live run). */
  append(rec) {
    const d = this.d;
    const i = d.t.length;
    const r = (v) => (v === null || v === undefined ? null : Math.round(v * 1e4) / 1e4);
    d.t.push(rec.t);
    d.tick.push(rec.tick);
    d.x.push(rec.pose ? r(rec.pose.x) : null);
    d.y.push(rec.pose ? r(rec.pose.y) : null);
    d.yaw.push(rec.pose ? r(rec.pose.yaw) : null);
    for (const k of [0, 1]) {
      d.cmd[k].push(r(rec.cmd[k]));
      d.vel[k].push(r(rec.vel[k]));
    }
    d.prox.names.forEach((name, s) => d.prox.values[s].push(r((rec.prox || {})[name])));
    const nodes = rec.nodes || {};
    this.paths.forEach((path, node) => {
      const letter = nodes[path] || "-";
      const c = this.changes[node];
      if (!c.letters.length || c.letters[c.letters.length - 1] !== letter) {
        c.at.push(i);
        c.letters.push(letter);
      }
    });
    for (const [key, value] of Object.entries(rec.bb || {})) {
      if (!d.bb[key]) d.bb[key] = [];
      d.bb[key].push([i, value]);
    }
    this.extendPath(i);
  }
}

const runs = DATA.runs.map((d, i) => new Run(d, i));

/** Whether a what-if run went on in the simulator (replay --continue sim): from run.d.simulated_from on. */
function simulated(run) {
  return run.d.simulated_from !== undefined && run.d.simulated_from !== null;
}
const single = runs.length === 1;

/* ------------------------------------------------------------------ state */

const state = {
  time: 0,
  playing: false,
  speed: 1,
  selected: null,
  breakpoints: [],
  lastFrame: 0,
  follow: DATA.live,
  zoom: false,
  ended: !DATA.live,
};

function span() {
  const starts = runs.filter((r) => r.n).map((r) => r.d.t[0]);
  const ends = runs.filter((r) => r.n).map((r) => r.d.t[r.n - 1]);
  return starts.length ? [Math.min(...starts), Math.max(...ends)] : [0, 0];
}

/* ------------------------------------------------------------------ the page's frame */

const header = el("header", { class: "bar" });
const titleBox = el("div", { class: "title" });
header.appendChild(titleBox);
titleBox.appendChild(el("h1", {}, runs.map((r) => r.d.label).join(" vs ") || "run"));
for (const run of runs) {
  const end = run.d.end || {};
  const verdict = el("span", {
    class: "verdict",
    "data-run": String(run.index),
    "data-verdict": end.status || "RUNNING",
  });
  verdict.textContent =
    (single ? "" : run.letter + ": ") +
    (end.status || "live") +
    (end.code ? " [" + end.code + "]" : "") +
    (run.d.seed !== null && run.d.seed !== undefined ? " · seed " + run.d.seed : "") +
    (simulated(run) ? " · simulated from " + run.d.simulated_from + " s" : "");
  titleBox.appendChild(verdict);
  const robot = run.d.robot;
  const model = el("span", { class: "robot-model", "data-run": String(run.index), "data-robot": robot.name });
  model.textContent = (single ? "" : run.letter + ": ") + "robot " + robot.name + (robot.assumed ? " (" + robot.assumed + ")" : "");
  if (robot.assumed) model.setAttribute("data-assumed", "true");
  titleBox.appendChild(model);
}
const announce = el("p", { id: "announce", role: "status", "aria-live": "polite" });
header.appendChild(announce);
const helpButton = el("button", { type: "button", class: "help-button", title: "Keyboard shortcuts (?)" }, "?");
header.appendChild(helpButton);
app.appendChild(header);

const stage = el("section", { class: "stage", "aria-label": "maze" });
const side = el("section", { class: "side" });
const timeline = el("section", { class: "timeline", "aria-label": "timeline" });
app.append(stage, side, timeline);
