/* Moving in time (seek, step, play at a speed), deep links (#t=, #tick=) and keys. */
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
