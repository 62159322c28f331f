/* Breakpoints: conditions on signals, statuses and events that stop the playback. */
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
