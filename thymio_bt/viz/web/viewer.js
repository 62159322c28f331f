/* thymio-bt's run viewer: one run (or two) of a mission, at any tick.
 *
 * Reads the JSON of <script id="run-data"> (thymio_bt/viz/page_data.py writes it) and draws the
 * maze, the robot with its rays, the path, the tree with each node's status, the blackboard, the
 * signals and the events as SVG and HTML. Plain JavaScript, no library, no request: the page works
 * from file:// and offline. The DOM contract that outside checks read is in docs/viewer.md:
 * [data-node][data-status] per tree node, [data-pose] on the robot, [data-time] (and data-tick) on
 * the clock, data-divergence on <html>, and #t= / #tick= deep links.
 */
"use strict";

(function () {
  const SVG = "http://www.w3.org/2000/svg";
  const STATUS = { S: "SUCCESS", F: "FAILURE", R: "RUNNING", "-": "INVALID", I: "IDLE" };
  const SPEEDS = [1, 5, 20];
  const EPS = 1e-9;
  const DATA = JSON.parse(document.getElementById("run-data").textContent);
  const app = document.getElementById("app");

  /* ------------------------------------------------------------------ small helpers */

  function el(tag, attrs, text) {
    const node = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function sv(tag, attrs, text) {
    const node = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function titled(node, text) {
    node.appendChild(sv("title", {}, text));
    return node;
  }

  /** The last index i of the sorted array a with a[i] <= v, or -1. */
  function lastAtOrBefore(a, v) {
    let lo = 0;
    let hi = a.length - 1;
    let found = -1;
    while (lo <= hi) {
      const mid = (lo + hi) >> 1;
      if (a[mid] <= v) {
        found = mid;
        lo = mid + 1;
      } else {
        hi = mid - 1;
      }
    }
    return found;
  }

  function fmt(v, digits) {
    return v === null || v === undefined ? "—" : Number(v).toFixed(digits);
  }

  function valueText(v) {
    return typeof v === "string" ? v : JSON.stringify(v);
  }

  function hue(text) {
    let h = 0;
    for (let i = 0; i < text.length; i++) h = (h * 31 + text.charCodeAt(i)) % 360;
    return "hsl(" + h + ", 55%, 62%)";
  }

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

  /* ------------------------------------------------------------------ the maze and robots */

  const sameMaze = runs.every((r) => JSON.stringify(r.d.maze) === JSON.stringify(runs[0].d.maze));
  const views = [];

  /** The part of the maze shown: where the robots went and a margin, within the maze; the whole maze before any pose. */
  function viewBox(group) {
    let [x0, y0, x1, y1] = group[0].d.maze.bounds;
    const empty = x0 === x1 && y0 === y1;
    let [px0, py0, px1, py1] = [Infinity, Infinity, -Infinity, -Infinity];
    for (const run of group) {
      for (let i = 0; i < run.n; i++) {
        if (run.d.x[i] === null) continue;
        px0 = Math.min(px0, run.d.x[i]);
        px1 = Math.max(px1, run.d.x[i]);
        py0 = Math.min(py0, run.d.y[i]);
        py1 = Math.max(py1, run.d.y[i]);
      }
    }
    const margin = 0.15;
    if (px0 <= px1) {
      if (empty) [x0, y0, x1, y1] = [px0 - margin, py0 - margin, px1 + margin, py1 + margin];
      else {
        x0 = Math.max(x0, px0 - margin);
        y0 = Math.max(y0, py0 - margin);
        x1 = Math.min(x1, px1 + margin);
        y1 = Math.min(y1, py1 + margin);
      }
    } else if (empty) {
      [x0, y0, x1, y1] = [-0.3, -0.3, 0.3, 0.3];
    }
    const pad = 0.03;
    return [x0 - pad, -y1 - pad, x1 - x0 + 2 * pad, y1 - y0 + 2 * pad];
  }

  function polygon(flat, cls) {
    const points = [];
    for (let i = 0; i < flat.length; i += 2) points.push(flat[i] + "," + -flat[i + 1]);
    return sv("polygon", { points: points.join(" "), class: cls });
  }

  function makeView(group) {
    const box = el("div", { class: "maze-box" });
    const box0 = viewBox(group).join(" ");
    const svg = sv("svg", { class: "maze", viewBox: box0, role: "img" });
    svg.appendChild(sv("title", {}, "maze " + group[0].d.maze.name));
    const maze = group[0].d.maze;
    for (const g of maze.goal) {
      svg.appendChild(
        sv("rect", {
          class: "goal",
          x: Math.min(g[0], g[2]),
          y: -Math.max(g[1], g[3]),
          width: Math.abs(g[2] - g[0]),
          height: Math.abs(g[3] - g[1]),
        }),
      );
    }
    const walls = sv("g", { class: "walls" });
    for (const w of maze.walls) walls.appendChild(polygon(w, "wall"));
    for (const o of maze.obstacles) walls.appendChild(polygon(o, "obstacle"));
    svg.appendChild(walls);
    const robots = [];
    for (const run of group) {
      const colour = "run-" + run.index;
      const full = sv("path", { class: "path-full " + colour, d: run.pathD });
      svg.appendChild(full);
      const done = sv("path", { class: "path-done " + colour, d: "" });
      svg.appendChild(done);
      const robot = sv("g", { class: "robot " + colour, "data-run": String(run.index), "data-pose": "" });
      const rays = run.d.robot.sensors.map((s) => {
        const ray = sv("line", { class: "ray", x1: s[1], y1: -s[2], x2: s[1], y2: -s[2] });
        robot.appendChild(titled(ray, s[0]));
        return ray;
      });
      robot.appendChild(polygon(run.d.robot.hull, "hull"));
      robot.appendChild(sv("line", { class: "heading", x1: 0, y1: 0, x2: 0.04, y2: 0 }));
      svg.appendChild(robot);
      robots.push({ run, robot, rays, done, full, shown: -2 });
    }
    box.appendChild(svg);
    const readings = el("table", { class: "readings" });
    const head = el("tr");
    head.appendChild(el("th", {}, single ? "sensor" : "sensor"));
    for (const r of group) head.appendChild(el("th", { class: "run-" + r.index }, single ? "reading" : r.letter));
    readings.appendChild(head);
    const cells = group[0].d.prox.names.map((name) => {
      const row = el("tr");
      row.appendChild(el("td", {}, name.replace(/_/g, " ")));
      const tds = group.map(() => el("td", { class: "num" }));
      row.append(...tds);
      readings.appendChild(row);
      return tds;
    });
    box.appendChild(readings);
    stage.appendChild(box);
    views.push({ robots, cells, svg, box: box0 });
  }

  if (sameMaze) makeView(runs);
  else runs.forEach((r) => makeView([r]));
  if (!sameMaze) stage.classList.add("two");
  if (!single) app.classList.add("two-runs");

  /** Zoomed in, the maze follows the view's first robot shown (a 16 x 16 maze's robot is small). */
  function frameView(view) {
    const pose = view.robots.map((e) => e.run.pose(e.shown)).find((p) => p);
    const half = 0.35;
    const box = state.zoom && pose ? [pose.x - half, -pose.y - half, 2 * half, 2 * half].join(" ") : view.box;
    if (view.svg.getAttribute("viewBox") !== box) view.svg.setAttribute("viewBox", box);
  }

  function drawRobots() {
    for (const view of views) {
      view.robots.forEach((entry, column) => {
        const { run, robot, rays, done } = entry;
        const i = run.indexAt(state.time);
        if (i === entry.shown) return;
        entry.shown = i;
        const pose = run.pose(i);
        done.setAttribute("d", i >= 0 ? run.pathD.slice(0, run.pathEnds[i]) : "");
        if (!pose) {
          robot.setAttribute("data-pose", "");
          robot.setAttribute("visibility", "hidden");
        } else {
          robot.removeAttribute("visibility");
          robot.setAttribute("data-pose", pose.x.toFixed(4) + " " + pose.y.toFixed(4) + " " + pose.yaw.toFixed(4));
          robot.setAttribute(
            "transform",
            "translate(" + pose.x + " " + -pose.y + ") rotate(" + (-pose.yaw * 180) / Math.PI + ")",
          );
        }
        robot.setAttribute("data-tick", i >= 0 ? String(run.d.tick[i]) : "");
        run.d.robot.sensors.forEach((s, k) => {
          const value = i >= 0 ? run.d.prox.values[k][i] : null;
          const length = value === null ? run.d.robot.range : value;
          rays[k].setAttribute("x2", s[1] + length * Math.cos(s[3]));
          rays[k].setAttribute("y2", -(s[2] + length * Math.sin(s[3])));
          rays[k].classList.toggle("hit", value !== null);
          view.cells[k][column].textContent = value === null ? "—" : (value * 100).toFixed(1) + " cm";
        });
      });
      frameView(view);
    }
  }

  /* ------------------------------------------------------------------ the trees */

  const trees = [];
  const treeBox = el("div", { class: "trees" + (single ? "" : " two") });
  side.appendChild(treeBox);

  function feedbacks(run) {
    const out = new Map();
    const add = (path, t, text) => {
      const node = run.nodeIndex.get(path);
      if (node === undefined || !text) return;
      if (!out.has(node)) out.set(node, []);
      out.get(node).push([run.indexAt(t), text]);
    };
    for (const e of run.events) {
      if (e.kind === "behaviour_end" && e.status === "FAILURE") add(e.path, e.t, e.reason || e.code || "FAILURE");
    }
    const end = run.d.end || {};
    if (end.failed_path && run.n) add(end.failed_path, run.d.t[run.n - 1], (end.code ? "[" + end.code + "] " : "") + (end.reason || ""));
    return out;
  }

  for (const run of runs) {
    const box = el("div", { class: "tree", "data-run": String(run.index) });
    box.appendChild(el("h2", {}, single ? "Tree" : "Tree " + run.letter));
    const root = el("ul", { role: "tree" });
    box.appendChild(root);
    const lists = [];
    const items = run.d.tree.map((row, node) => {
      const [path, name, kind, parent] = row;
      const li = el("li", { role: "treeitem" });
      const item = el("div", { class: "node", "data-node": path, "data-status": "INVALID", "data-run": String(run.index), tabindex: "-1" });
      item.appendChild(el("span", { class: "name" }, name));
      if (kind && kind !== name) item.appendChild(el("span", { class: "kind" }, kind));
      const feedback = el("span", { class: "feedback" });
      item.appendChild(feedback);
      item.addEventListener("click", () => selectNode(path));
      li.appendChild(item);
      const children = el("ul", { role: "group" });
      li.appendChild(children);
      lists[node] = children;
      (parent >= 0 && lists[parent] ? lists[parent] : root).appendChild(li);
      return { item, feedback, shown: "" };
    });
    treeBox.appendChild(box);
    trees.push({ run, items, feedbacks: feedbacks(run) });
  }

  function drawTrees() {
    for (const tree of trees) {
      const i = tree.run.indexAt(state.time);
      tree.items.forEach((entry, node) => {
        const letter = i < 0 ? "-" : tree.run.status(node, i);
        const status = STATUS[letter] || "INVALID";
        if (entry.shown !== status) {
          entry.item.setAttribute("data-status", status);
          entry.shown = status;
        }

        let text = "";
        const notes = tree.feedbacks.get(node);
        if (letter === "F" && notes) {
          for (const [at, note] of notes) if (at <= i) text = note;
        }
        if (entry.feedback.textContent !== text) entry.feedback.textContent = text;
      });
    }
    if (!single) markDifferences(trees[0], trees[1]);
  }

  /** Outline the nodes whose status differs between the two runs at the shown moment. */
  function markDifferences(a, b) {
    const inA = new Map(a.items.map((entry, node) => [a.run.paths[node], entry]));
    b.items.forEach((entry, node) => {
      const other = inA.get(b.run.paths[node]);
      const differs = other !== undefined && other.shown !== entry.shown;
      entry.item.classList.toggle("differs", differs);
      if (other) other.item.classList.toggle("differs", differs);
    });
  }

  /* ------------------------------------------------------------------ the blackboards */

  const boards = [];
  for (const run of runs) {
    const box = el("div", { class: "board", "data-run": String(run.index) });
    box.appendChild(el("h2", {}, single ? "Blackboard" : "Blackboard " + run.letter));
    const empty = el("p", { class: "empty" }, "(nothing on the blackboard yet)");
    const table = el("table");
    box.append(empty, table);
    side.appendChild(box);
    boards.push({ run, table, empty, rows: new Map() });
  }

  function drawBoards() {
    for (const board of boards) {
      const { run, table, rows, empty } = board;
      const i = run.indexAt(state.time);
      empty.hidden = Object.keys(run.d.bb).length > 0;
      for (const key of Object.keys(run.d.bb)) {
        if (!rows.has(key)) {
          const row = el("tr", { class: "key", "data-key": key });
          const th = el("th", { scope: "row" });
          const toggle = el("button", { type: "button", title: "history of " + key, "aria-expanded": "false" }, key);
          th.appendChild(toggle);
          const td = el("td");
          row.append(th, td);
          const history = el("tr", { class: "history", hidden: "" });
          const cell = el("td", { colspan: "2" });
          history.appendChild(cell);
          toggle.addEventListener("click", () => {
            const open = history.hasAttribute("hidden");
            if (open) history.removeAttribute("hidden");
            else history.setAttribute("hidden", "");
            toggle.setAttribute("aria-expanded", String(open));
            entry.drawn = -1;
            drawBoards();
          });
          table.append(row, history);
          const entry = { td, history, cell, shown: null, drawn: -1 };
          rows.set(key, entry);
        }
        const entry = rows.get(key);
        const change = i >= 0 ? run.bbAt(key, i) : undefined;
        const text = change === undefined ? "—" : valueText(change[1]);
        if (entry.td.textContent !== text) entry.td.textContent = text;
        if (!entry.history.hasAttribute("hidden")) drawHistory(run, key, entry, i);
      }
    }
  }

  function drawHistory(run, key, entry, i) {
    const changes = run.d.bb[key];
    if (entry.drawn !== changes.length) {
      entry.cell.textContent = "";
      const list = el("ol", { class: "changes" });
      for (const [at, value] of changes.slice(-200)) {
        const li = el("li", { "data-index": String(at) });
        const jump = el("button", { type: "button" }, "t = " + run.d.t[at] + " s");
        jump.addEventListener("click", () => seek(run.d.t[at], true));
        li.append(jump, el("span", {}, " " + valueText(value)));
        list.appendChild(li);
      }
      entry.cell.appendChild(list);
      entry.drawn = changes.length;
    }
    for (const li of entry.cell.querySelectorAll("li")) {
      li.classList.toggle("now", Number(li.getAttribute("data-index")) <= i);
    }
  }

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

  /* ------------------------------------------------------------------ breakpoints */

  const panel = el("details", { class: "breakpoints" });
  panel.appendChild(el("summary", {}, "Breakpoints"));
  const form = el("div", { class: "bp-form" });
  const nodeSelect = el("select", { "aria-label": "node" });
  for (const path of runs[0].paths) nodeSelect.appendChild(el("option", { value: path }, path));
  const whenSelect = el("select", { "aria-label": "when" });
  for (const w of ["starts", "ends", "fails"]) whenSelect.appendChild(el("option", { value: w }, w));
  const addNode = el("button", { type: "button", title: "Break on this node (b)" }, "add");
  addNode.addEventListener("click", () => addBreakpoint({ node: nodeSelect.value, when: whenSelect.value }));
  const condition = el("input", { type: "text", placeholder: "front_center < 0.05", "aria-label": "condition" });
  const addCondition = el("button", { type: "button" }, "add condition");
  addCondition.addEventListener("click", () => {
    const parsed = parseCondition(condition.value);
    if (parsed) addBreakpoint(parsed);
    else say("A condition is NAME OP VALUE: a blackboard key, x, y, yaw, v, w, t or a sensor; OP one of < <= > >= == !=.");
  });
  form.append(nodeSelect, whenSelect, addNode, condition, addCondition);
  const list = el("ul", { class: "bp-list" });
  panel.append(form, list);
  timeline.appendChild(panel);

  function parseCondition(text) {
    const m = /^\s*([\w/.\-]+)\s*(<=|>=|==|!=|<|>)\s*(.+?)\s*$/.exec(text);
    if (!m) return null;
    let value = m[3];
    try {
      value = JSON.parse(value);
    } catch (_error) {
      value = value.replace(/^'(.*)'$/, "$1");
    }
    return { name: m[1], op: m[2], value, text: m[1] + " " + m[2] + " " + m[3] };
  }

  function signal(run, name, i) {
    const d = run.d;
    const direct = { t: d.t, x: d.x, y: d.y, yaw: d.yaw, v: d.vel[0], w: d.vel[1], cmd_v: d.cmd[0], cmd_w: d.cmd[1] };
    if (direct[name]) return direct[name][i];
    const s = d.prox.names.indexOf(name);
    if (s >= 0) return d.prox.values[s][i];
    for (const key of [name, "/" + name]) {
      if (d.bb[key]) {
        const change = run.bbAt(key, i);
        return change === undefined ? undefined : change[1];
      }
    }
    return undefined;
  }

  function holds(bp, run, i) {
    const v = signal(run, bp.name, i);
    if (v === undefined) return false;
    switch (bp.op) {
      case "<":
        return v !== null && v < bp.value;
      case "<=":
        return v !== null && v <= bp.value;
      case ">":
        return v !== null && v > bp.value;
      case ">=":
        return v !== null && v >= bp.value;
      case "==":
        return JSON.stringify(v) === JSON.stringify(bp.value);
      default:
        return JSON.stringify(v) !== JSON.stringify(bp.value);
    }
  }

  function eventAt(run, i, path, kind, status) {
    const t = run.d.t[i];
    const prev = i > 0 ? run.d.t[i - 1] : -Infinity;
    return run.events.some((e) => e.path === path && e.kind === kind && (!status || e.status === status) && e.t > prev + EPS && e.t <= t + EPS);
  }

  /** Whether breakpoint bp fires at index i of run: a node starts, ends or fails there, or a condition becomes true. */
  function fires(bp, run, i) {
    if (i < 1) return false;
    if (bp.op) return holds(bp, run, i) && !holds(bp, run, i - 1);
    const node = run.nodeIndex.get(bp.node);
    if (node === undefined) return false;
    const now = run.status(node, i);
    const before = run.status(node, i - 1);
    if (bp.when === "starts") return (now === "R" && before !== "R") || eventAt(run, i, bp.node, "behaviour_start");
    if (bp.when === "ends") return (before === "R" && now !== "R" && now !== "-") || eventAt(run, i, bp.node, "behaviour_end");
    return (now === "F" && before !== "F") || eventAt(run, i, bp.node, "behaviour_end", "FAILURE");
  }

  function addBreakpoint(bp) {
    bp.label = bp.op ? "when " + bp.text : bp.node + " " + bp.when;
    state.breakpoints.push(bp);
    const li = el("li", {}, bp.label + " ");
    const remove = el("button", { type: "button", title: "remove" }, "✕");
    remove.addEventListener("click", () => {
      state.breakpoints = state.breakpoints.filter((b) => b !== bp);
      li.remove();
    });
    li.appendChild(remove);
    list.appendChild(li);
    panel.open = true;
    say("Breakpoint: " + bp.label + ".");
  }

  /** The first breakpoint hit after time a up to time b: [time, label] or null. */
  function breakBetween(a, b) {
    let best = null;
    if (!state.breakpoints.length) return null;
    for (const run of runs) {
      const from = run.indexAt(a) + 1;
      const to = run.indexAt(b);
      for (let i = Math.max(from, 1); i <= to; i++) {
        if (best && run.d.t[i] >= best[0]) break;
        const bp = state.breakpoints.find((x) => fires(x, run, i));
        if (bp) {
          best = [run.d.t[i], (single ? "" : run.letter + ": ") + bp.label];
          break;
        }
      }
    }
    return best;
  }

  /* ------------------------------------------------------------------ moving in time */

  function say(text) {
    announce.textContent = text;
  }

  function times() {
    if (single) return runs[0].d.t;
    return Array.from(new Set(runs.flatMap((r) => r.d.t))).sort((a, b) => a - b);
  }

  function render() {
    const [t0, t1] = span();
    state.time = Math.min(Math.max(state.time, t0), t1);
    const shown = runs.filter((r) => r.n).map((r) => r.d.t[r.indexAt(state.time)]);
    const time = shown.length ? Math.max(...shown) : 0;
    const first = runs[0].indexAt(state.time);
    clock.setAttribute("data-time", String(time));
    clock.setAttribute("data-tick", first >= 0 ? String(runs[0].d.tick[first]) : "");
    clock.textContent = "t = " + time.toFixed(1) + " s · tick " + (first >= 0 ? runs[0].d.tick[first] : "—");
    drawRobots();
    drawTrees();
    drawBoards();
    drawCursor();
  }

  function remember() {
    if (state.playing) return;
    try {
      history.replaceState(null, "", "#t=" + clock.getAttribute("data-time"));
    } catch (_error) {
      /* an iframe without a URL of its own (Jupyter's srcdoc) keeps no hash: nothing to do */
    }
  }

  function seek(t, byUser) {
    state.time = t;
    state.follow = DATA.live && t >= span()[1];
    render();
    if (byUser) remember();
  }

  function step(direction) {
    setPlaying(false);
    const all = times();
    const at = lastAtOrBefore(all, state.time + EPS);
    const next = Math.min(Math.max(at + direction, 0), all.length - 1);
    if (all.length) seek(all[next], true);
  }

  function eventTimes() {
    const all = runs.flatMap((r) => r.events.map((e) => e.t));
    if (DATA.divergence) all.push(DATA.divergence.time);
    for (const r of runs) if (r.n && r.d.end && r.d.end.status) all.push(r.d.t[r.n - 1]);
    return Array.from(new Set(all)).sort((a, b) => a - b);
  }

  function jumpEvent(direction) {
    setPlaying(false);
    const all = eventTimes();
    const target = direction > 0 ? all.find((t) => t > state.time + EPS) : all.filter((t) => t < state.time - EPS).pop();
    if (target === undefined) say(direction > 0 ? "No event after this moment." : "No event before this moment.");
    else seek(target, true);
  }

  function setSpeed(s) {
    state.speed = s;
    speedButtons.forEach((b, k) => b.setAttribute("aria-pressed", String(SPEEDS[k] === s)));
  }

  function setPlaying(on) {
    if (on && !DATA.live && state.time >= span()[1] - EPS) seek(span()[0], false);
    state.playing = on;
    playButton.textContent = on ? "▮▮" : "▶";
    playButton.setAttribute("aria-pressed", String(on));
    if (on) {
      state.lastFrame = performance.now();
      requestAnimationFrame(frame);
    } else {
      remember();
    }
  }

  function frame(now) {
    if (!state.playing) return;
    const dt = Math.min((now - state.lastFrame) / 1000, 0.25);
    state.lastFrame = now;
    const from = state.time;
    let to = from + dt * state.speed;
    const hit = breakBetween(from, to);
    const end = span()[1];
    if (hit) {
      seek(hit[0], false);
      say("Paused at breakpoint " + hit[1] + ", t = " + hit[0] + " s.");
      setPlaying(false);
      return;
    }
    if (to >= end) to = end;
    seek(to, false);
    if (to >= end && state.ended) {
      setPlaying(false);
      return;
    }
    requestAnimationFrame(frame);
  }

  function toggleZoom() {
    state.zoom = !state.zoom;
    zoomButton.setAttribute("aria-pressed", String(state.zoom));
    views.forEach(frameView);
  }

  function selectNode(path) {
    state.selected = path;
    nodeSelect.value = path;
    for (const item of document.querySelectorAll(".node.selected")) item.classList.remove("selected");
    for (const item of document.querySelectorAll(".node")) {
      if (item.getAttribute("data-node") === path) item.classList.add("selected");
    }
  }

  /* ------------------------------------------------------------------ deep links and keys */

  function fromHash() {
    const m = /^#(t|tick)=(-?[0-9.]+(?:e-?[0-9]+)?)$/.exec(location.hash);
    if (!m) return false;
    const v = Number(m[2]);
    if (m[1] === "t") {
      seek(v, false);
    } else {
      const run = runs[0];
      const at = lastAtOrBefore(run.d.tick, v);
      seek(run.n ? run.d.t[Math.max(at, 0)] : 0, false);
    }
    return true;
  }

  const help = el("div", { class: "help", hidden: "" });
  const keys = [
    ["space", "play or pause"],
    ["← →", "one tick back or forward"],
    ["shift ← →", "one second back or forward"],
    ["[ ]", "previous or next event"],
    ["1 2 3", "play at 1x, 5x, 20x"],
    ["home end", "start or end of the run"],
    ["b", "add the breakpoint chosen below (click a node to choose it)"],
    ["d", "go to the first divergence (two runs)"],
    ["z", "follow the robot up close, or the whole maze"],
    ["?", "this help"],
  ];
  const dl = el("dl");
  for (const [k, what] of keys) dl.append(el("dt", {}, k), el("dd", {}, what));
  help.append(el("h2", {}, "Keyboard"), dl);
  app.appendChild(help);
  const toggleHelp = () => (help.hasAttribute("hidden") ? help.removeAttribute("hidden") : help.setAttribute("hidden", ""));
  helpButton.addEventListener("click", toggleHelp);

  document.addEventListener("keydown", (event) => {
    const target = event.target;
    if (target && (target.tagName === "INPUT" && target.type === "text")) return;
    if (target && target.tagName === "SELECT") return;
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    const actions = {
      " ": () => setPlaying(!state.playing),
      ArrowLeft: () => (event.shiftKey ? seekBy(-1) : step(-1)),
      ArrowRight: () => (event.shiftKey ? seekBy(1) : step(1)),
      "[": () => jumpEvent(-1),
      "]": () => jumpEvent(1),
      1: () => setSpeed(1),
      2: () => setSpeed(5),
      3: () => setSpeed(20),
      Home: () => seekUser(span()[0]),
      End: () => seekUser(span()[1]),
      b: () => addBreakpoint({ node: nodeSelect.value, when: whenSelect.value }),
      d: () => DATA.divergence && seekUser(DATA.divergence.time),
      z: toggleZoom,
      "?": toggleHelp,
    };
    const action = actions[event.key];
    if (action) {
      event.preventDefault();
      action();
    }
  });

  function seekUser(t) {
    setPlaying(false);
    seek(t, true);
  }

  function seekBy(seconds) {
    seekUser(state.time + seconds);
  }

  /* ------------------------------------------------------------------ a live run */

  async function poll() {
    const run = runs[0];
    try {
      const answer = await fetch("ticks?from=" + run.n, { cache: "no-store" });
      const data = await answer.json();
      const following = state.follow || !run.n;
      if (!run.n && data.ticks.length) say("Live: following the run (scrub to look back, End to follow again).");
      for (const rec of data.ticks) run.append(rec);
      if (data.events) run.events = data.events;
      if (data.ticks.length || data.end) {
        if (data.end) {
          run.d.end = data.end;
          state.ended = true;
          const verdict = document.querySelector('.verdict[data-run="0"]');
          verdict.setAttribute("data-verdict", data.end.status);
          verdict.textContent = data.end.status + (data.end.code ? " [" + data.end.code + "]" : "");
          trees[0].feedbacks = feedbacks(run);
          say("The run ended: " + data.end.status + (data.end.reason ? ", " + data.end.reason : "") + ".");
        }
        drawTimeline();
        for (const view of views) {
          for (const entry of view.robots) {
            entry.shown = -2;
            entry.full.setAttribute("d", entry.run.pathD);
          }
        }
        if (following && !state.playing) seek(span()[1], false);
        else render();
      }
      if (!data.end) setTimeout(poll, 200);
    } catch (_error) {
      say("The live run's server stopped: the page keeps what it received.");
    }
  }

  /* ------------------------------------------------------------------ start */

  setSpeed(1);
  drawTimeline();
  if (DATA.divergence) {
    document.documentElement.setAttribute("data-divergence", String(DATA.divergence.time));
    say("The runs first diverge at t = " + DATA.divergence.time + " s (tick " + DATA.divergence.tick + "): " + DATA.divergence.reason + ".");
  } else if (!single) {
    say("The two runs do not diverge.");
  }
  for (const run of runs.filter((r) => r.d.note)) {
    say((announce.textContent + " " + (single ? "" : run.letter + ": ") + "No robot: " + run.d.note + ".").trim());
  }
  for (const run of runs.filter(simulated)) {
    say(announce.textContent + " " + run.letter + " is simulated from t = " + run.d.simulated_from + " s (--continue sim).");
  }
  if (!fromHash()) seek(span()[0], false);
  window.addEventListener("hashchange", fromHash);
  if (DATA.live) {
    say("Live: waiting for ticks…");
    poll();
  }
})();
