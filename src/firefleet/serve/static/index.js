// The index of runs: one row per run folder the server was given.
"use strict";
(async function () {
  const response = await fetch("/api/runs");
  const runs = await response.json();
  const body = document.querySelector("#runs tbody");
  for (const run of runs) {
    const row = document.createElement("tr");
    row.dataset.run = run.id;
    const link = document.createElement("a");
    link.href = "/run/" + encodeURIComponent(run.id);
    link.textContent = run.name;
    const cells = [link, run.scenario, run.date, run.seed === null ? "-" : String(run.seed)];
    for (const content of cells) {
      const cell = document.createElement("td");
      if (typeof content === "string") cell.textContent = content; else cell.appendChild(content);
      row.appendChild(cell);
    }
    const claims = document.createElement("td");
    claims.className = "num claims " + (run.claims_passed === run.claims_total ? "ok" : "bad");
    claims.textContent = run.claims_total ? run.claims_passed + " / " + run.claims_total : "-";
    row.appendChild(claims);
    const replay = document.createElement("td");
    replay.textContent = run.replay || "-";
    row.appendChild(replay);
    body.appendChild(row);
  }
  document.getElementById("count").textContent = runs.length + " run(s)";
  document.body.dataset.ready = "1";
})();
