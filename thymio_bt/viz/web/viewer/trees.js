/* The trees with each node's status, and the blackboards with each key's history. */
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
