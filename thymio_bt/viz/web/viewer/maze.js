/* The maze and the robots: the SVG view, its zoom, each run's robot, rays and path. */
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
