/* A live run (the page polls its server for new ticks), then the start of the page. */
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
