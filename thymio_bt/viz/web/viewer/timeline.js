/* The timeline: signal charts, event marks, verdicts and the cursor. */
/* ------------------------------------------------------------------ the timeline */

const controls = el("div", { class: "controls" });
const button = (label, title, action) => {
  const b = el("button", { type: "button", title }, label);
  b.addEventListener("click", action);
  controls.appendChild(b);
  return b;
};
button("◀◀", "Previous event ([)", () => jumpEvent(-1));
button("|◀", "One tick back (←)", () => step(-1));
const playButton = button("▶", "Play or pause (space)", () => setPlaying(!state.playing));
button("▶|", "One tick forward (→)", () => step(1));
button("▶▶", "Next event (])", () => jumpEvent(1));
const speedButtons = SPEEDS.map((s, k) => {
  const b = button(s + "x", "Play at " + s + "x (" + (k + 1) + ")", () => setSpeed(s));
  b.classList.add("speed");
  return b;
});
if (DATA.divergence) button("≠", "Go to the first divergence (d)", () => seek(DATA.divergence.time, true));
const zoomButton = button("zoom", "Follow the robot up close, or show the whole maze (z)", () => toggleZoom());
const clock = el("output", { id: "clock", class: "clock", "data-time": "0", "data-tick": "0" }, "t = 0 s");
controls.appendChild(clock);
timeline.appendChild(controls);

const scrub = el("input", { type: "range", id: "scrub", min: "0", max: "0", step: "any", value: "0", "aria-label": "time" });
scrub.addEventListener("input", () => {
  setPlaying(false);
  seek(Number(scrub.value), true);
});
timeline.appendChild(scrub);

const tracks = el("div", { class: "tracks" });
timeline.appendChild(tracks);
let cursors = [];

function xOf(t) {
  const [t0, t1] = span();
  return t1 > t0 ? ((t - t0) / (t1 - t0)) * 1000 : 0;
}

function chart(cls, height, label) {
  const wrap = el("div", { class: "chart " + cls });
  wrap.appendChild(el("span", { class: "chart-label" }, label));
  const svg = sv("svg", { viewBox: "0 0 1000 " + height, preserveAspectRatio: "none", height: String(height) });
  svg.addEventListener("click", (event) => {
    const box = svg.getBoundingClientRect();
    const [t0, t1] = span();
    setPlaying(false);
    seek(t0 + ((event.clientX - box.left) / box.width) * (t1 - t0), true);
  });
  wrap.appendChild(svg);
  tracks.appendChild(wrap);
  return svg;
}

/** A signal as a line over time; a missing value (null) is ``missing``, or a gap in the line. */
function line(svg, values, times, lo, hi, height, cls, title, missing) {
  let d = "";
  let gap = true;
  for (let i = 0; i < values.length; i++) {
    const v = values[i] === null ? missing : values[i];
    if (v === undefined) {
      gap = true;
      continue;
    }
    const y = height - ((v - lo) / (hi - lo || 1)) * (height - 4) - 2;
    d += (gap ? "M" : "L") + xOf(times[i]).toFixed(1) + " " + y.toFixed(1);
    gap = false;
  }
  if (d) svg.appendChild(titled(sv("path", { d, class: cls }), title));
}

function drawTimeline() {
  tracks.textContent = "";
  cursors = [];
  const [t0, t1] = span();
  scrub.min = String(t0);
  scrub.max = String(t1);
  const ev = chart("events", 18 * runs.length + 8, "events");
  runs.forEach((run, k) => {
    const y = 4 + 18 * k;
    const open = new Map();
    if (simulated(run) && run.n) {
      const x = xOf(run.d.simulated_from);
      const band = sv("rect", {
        class: "simulated",
        "data-run": String(run.index),
        "data-simulated-from": String(run.d.simulated_from),
        x,
        y: y - 3,
        width: Math.max(xOf(run.d.t[run.n - 1]) - x, 1.5),
        height: 18,
      });
      ev.appendChild(titled(band, (single ? "" : run.letter + ": ") + "simulated from t = " + run.d.simulated_from + " s (--continue sim), not the recording"));
    }
    for (const e of run.events) {
      if (e.kind === "behaviour_start") open.set(e.path, e.t);
      else if (e.kind === "behaviour_end") {
        const start = open.has(e.path) ? open.get(e.path) : e.t;
        open.delete(e.path);
        const x = xOf(start);
        const rect = sv("rect", {
          class: "span" + (e.status === "FAILURE" ? " failed" : ""),
          x,
          y,
          width: Math.max(xOf(e.t) - x, 1.5),
          height: 12,
          fill: hue(e.name || ""),
        });
        ev.appendChild(titled(rect, (single ? "" : run.letter + ": ") + e.name + " " + start + "–" + e.t + " s " + (e.status || "")));
      } else {
        const mark = sv("rect", { class: "mark " + e.kind, x: xOf(e.t) - 1.5, y: y - 2, width: 3, height: 16 });
        const said = e.kind === "verdict" ? "missed " + e.name + (e.reason ? ": " + e.reason : "") : e.kind;
        ev.appendChild(titled(mark, (single ? "" : run.letter + ": ") + said + " at " + e.t + " s"));
      }
    }
    for (const [path, start] of open) {
      const x = xOf(start);
      ev.appendChild(titled(sv("rect", { class: "span open", x, y, width: Math.max(xOf(t1) - x, 1.5), height: 12 }), path));
    }
    const end = run.d.end || {};
    if (end.status && end.status !== "SUCCESS" && run.n) {
      const x = xOf(run.d.t[run.n - 1]);
      ev.appendChild(titled(sv("rect", { class: "mark end", x: x - 2, y: y - 2, width: 4, height: 16 }), end.status + ": " + (end.reason || "")));
    }
  });
  if (DATA.divergence) {
    const x = xOf(DATA.divergence.time);
    ev.appendChild(titled(sv("line", { class: "divergence", x1: x, x2: x, y1: 0, y2: 18 * runs.length + 8 }), "first divergence at t = " + DATA.divergence.time + " s: " + DATA.divergence.reason));
  }
  for (const run of runs) {
    const prefix = single ? "" : run.letter + ": ";
    const speed = chart("signals", 60, prefix + "speed m/s (command dashed)");
    const all = run.d.cmd[0].concat(run.d.vel[0]).filter((v) => v !== null);
    const lo = Math.min(0, ...all.slice(0, 50000));
    const hi = Math.max(0.01, ...all.slice(0, 50000));
    line(speed, run.d.cmd[0], run.d.t, lo, hi, 60, "cmd", "commanded linear speed");
    line(speed, run.d.vel[0], run.d.t, lo, hi, 60, "vel", "linear speed");
    const turn = chart("signals", 50, prefix + "turn rad/s");
    line(turn, run.d.vel[1], run.d.t, -2.5, 2.5, 50, "vel turn", "angular speed");
    const prox = chart("signals", 70, prefix + "proximity m");
    run.d.prox.names.forEach((name, s) => {
      line(prox, run.d.prox.values[s], run.d.t, 0, run.d.robot.range, 70, "prox prox-" + s, name, run.d.robot.range);
    });
  }
  for (const svg of tracks.querySelectorAll("svg")) {
    const cursor = sv("line", { class: "cursor", x1: 0, x2: 0, y1: 0, y2: 200 });
    svg.appendChild(cursor);
    cursors.push(cursor);
  }
}

function drawCursor() {
  const x = xOf(state.time);
  for (const c of cursors) {
    c.setAttribute("x1", x);
    c.setAttribute("x2", x);
  }
  scrub.value = String(state.time);
}
