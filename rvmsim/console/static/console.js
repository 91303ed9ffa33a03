// rvmsim console: the page's logic (hand-written, no libraries).
// Every string from the server is set with textContent, never as HTML.
// Latest value wins: at most one evaluation is in flight; a newer value replaces the pending
// one, so a dragged slider never queues stale frames.
"use strict";
(() => {
  const token = new URLSearchParams(location.search).get("token") || "";
  const $ = (id) => document.getElementById(id);
  const state = {
    session: null, current: {}, history: [], inflight: false, pending: null,
    annotate: false, b: null, bResult: null, last: null, timings: [], server: [], frames: 0,
    inputs: 0, controls: {},
  };
  window.rvmConsole = state;  // for the tests and tools/bench_console.py

  // api(path): GET; api(path, body): POST of a JSON body (saves); api(path, null, query):
  // GET with ?q=JSON (evaluations, which change nothing).
  async function api(path, body, query) {
    const headers = {"Content-Type": "application/json"};
    if (token) headers["X-Rvm-Token"] = token;
    const url = query ? `${path}?q=${encodeURIComponent(JSON.stringify(query))}` : path;
    const r = await fetch(url, {method: body ? "POST" : "GET", headers,
                                body: body ? JSON.stringify(body) : undefined});
    let doc;
    try { doc = await r.json(); } catch (e) { doc = {error: `HTTP ${r.status}`}; }
    if (!r.ok) throw new Error(doc.error || `HTTP ${r.status}`);
    return doc;
  }

  function say(text, kind) {
    const m = $("message");
    m.textContent = text;
    m.className = text ? kind : "";
  }

  function cell(row, text, cls) {
    const td = document.createElement("td");
    td.textContent = text;
    if (cls) td.className = cls;
    row.appendChild(td);
    return td;
  }

  const fmt = (x) => (x === null || x === undefined) ? "—" : String(Number(Number(x).toPrecision(4)));
  const num = (x) => (x === null || x === undefined) ? "—" : (Math.abs(x) >= 1e4 ? x.toExponential(3) : x.toFixed(3));
  const status = (i) => !i.enabled ? "off" : (i.passed ? "pass" : "fail");

  // ------------------------------------------------------------------ evaluation
  function request(t0) {
    state.inputs += 1;
    state.pending = {params: {...state.current}, annotate: state.annotate,
                     t0: t0 === undefined ? performance.now() : t0};
    if (!state.inflight) pump();
  }

  async function pump() {
    const job = state.pending;
    state.pending = null;
    if (!job) return;
    state.inflight = true;
    try {
      const doc = await api("/api/evaluate", null, {params: job.params, annotate: job.annotate});
      const tJson = performance.now();
      const img = $("rvm");
      img.src = doc.annotated || doc.image;
      await img.decode();
      const tImage = performance.now();
      showEcs(doc);
      showRoi(doc.roi);
      $("ab-a").src = doc.image;
      $("ab-a-cap").textContent = `A: current — EC score ${fmt(doc.ec_score)}, ${doc.passed ? "all pass" : "not all pass"}`;
      state.last = doc;
      state.frames += 1;
      state.timings.push(performance.now() - job.t0);
      state.server.push({...doc.timings_ms, page_json: tJson - job.t0, page_image: tImage - tJson,
                         page_table: performance.now() - tImage});
      document.body.dataset.frame = String(doc.frame);
      if ($("message").className === "error") say("", "");
    } catch (e) {
      say(e.message, "error");
    } finally {
      state.inflight = false;
      if (state.pending) pump();
    }
  }

  function showEcs(doc) {
    const score = $("score");
    score.textContent = `EC score ${fmt(doc.ec_score)} · ${doc.passed ? "all pass" : "not all pass"}`;
    score.className = "badge " + (doc.passed ? "pass" : "fail");
    const body = $("ec-table").tBodies[0];
    body.replaceChildren();
    const bItems = {};
    if (state.bResult) for (const i of state.bResult.ecs) bItems[i.id] = i;
    for (const i of doc.ecs) {
      const tr = document.createElement("tr");
      const st = status(i);
      tr.className = st;
      tr.dataset.ec = i.id;
      cell(tr, i.id);
      cell(tr, i.name);
      cell(tr, num(i.value), "num value");
      cell(tr, i.unit);
      cell(tr, `[${i.range[0] === null ? "–" : i.range[0]}, ${i.range[1] === null ? "–" : i.range[1]}]`, "num");
      cell(tr, i.score.toFixed(4), "num score");
      cell(tr, st, "res");
      const b = bItems[i.id];
      cell(tr, b ? num(b.value) : "", "num");
      cell(tr, b ? status(b) : "", b ? status(b) : "");
      body.appendChild(tr);
    }
  }

  function showRoi(points) {
    $("roi-line").setAttribute("points", points.map((p) => `${p[0]},${p[1]}`).join(" "));
  }

  async function setB(params, caption) {
    try {
      const doc = await api("/api/evaluate", null, {params});
      state.b = params;
      state.bResult = doc;
      $("ab-b").src = doc.image;
      $("ab-b-cap").textContent = `B: ${caption} — EC score ${fmt(doc.ec_score)}, ${doc.passed ? "all pass" : "not all pass"}`;
      if (state.last) showEcs(state.last);
    } catch (e) {
      say(e.message, "error");
    }
  }

  // ------------------------------------------------------------------ controls
  function syncControls() {
    for (const [name, c] of Object.entries(state.controls)) {
      c.slider.value = String(state.current[name]);
      c.box.value = String(Number(state.current[name].toPrecision(7)));
    }
  }

  function commit(params) {  // a new setting that undo can go back from
    state.history.push({...state.current});
    state.current = {...params};
    syncControls();
    request();
  }

  function buildControl(spec) {
    const div = document.createElement("div");
    div.className = "control" + (spec.tuned ? " tuned" : "");
    div.dataset.param = spec.name;
    const label = document.createElement("label");
    label.className = "name";
    label.textContent = `${spec.paper_name}${spec.unit ? " (" + spec.unit + ")" : ""}`;
    label.title = spec.note;
    const slider = document.createElement("input");
    slider.type = "range";
    slider.min = String(spec.low);
    slider.max = String(spec.high);
    slider.step = String((spec.high - spec.low) / 1000);
    slider.name = spec.name;
    slider.setAttribute("aria-label", spec.name);
    const box = document.createElement("input");
    box.type = "number";
    box.step = "any";
    box.name = spec.name;
    box.setAttribute("aria-label", spec.name + " value");
    const range = document.createElement("div");
    range.className = "range";
    const unit = spec.unit ? " " + spec.unit : "";
    range.textContent = (spec.tuned ? `tuned; search [${fmt(spec.low)}, ${fmt(spec.high)}]${unit}; ` : "not tuned; ")
      + `allowed [${spec.spec_low}, ${spec.spec_high}]${unit}; default ${spec.default}`;
    let before = null;
    slider.addEventListener("pointerdown", () => { before = {...state.current}; });
    slider.addEventListener("input", (ev) => {
      if (before === null) before = {...state.current};
      state.current[spec.name] = Number(slider.value);
      box.value = String(Number(Number(slider.value).toPrecision(7)));
      request(ev.timeStamp || performance.now());
    });
    slider.addEventListener("change", () => {
      if (before !== null) state.history.push(before);
      before = null;
    });
    box.addEventListener("change", () => {
      const v = Number(box.value);
      if (box.value.trim() === "" || !Number.isFinite(v)) {
        say(`${spec.name}: ${JSON.stringify(box.value)} is not a number`, "error");
        return;
      }
      commit({...state.current, [spec.name]: v});
    });
    label.htmlFor = `box-${spec.name}`;
    box.id = `box-${spec.name}`;
    slider.id = `slider-${spec.name}`;
    div.append(label, slider, box, range);
    state.controls[spec.name] = {slider, box, spec};
    return div;
  }

  function buildCandidates(cands) {
    const body = $("candidates").tBodies[0];
    if (!cands.length) {
      const tr = document.createElement("tr");
      cell(tr, "no run: the paper's defaults").colSpan = 5;
      body.appendChild(tr);
      return;
    }
    for (const c of cands) {
      const tr = document.createElement("tr");
      tr.dataset.rank = String(c.rank);
      cell(tr, `#${c.rank}`);
      cell(tr, fmt(c.score), "num");
      cell(tr, c.passed ? "pass" : "fail", c.passed ? "pass" : "fail");
      cell(tr, c.differs || (c.rank === 1 ? "rank 1" : `trial ${c.trial}`));
      const td = cell(tr, "");
      const load = document.createElement("button");
      load.type = "button";
      load.textContent = "Load";
      load.className = "load";
      load.addEventListener("click", () => { commit(c.params); say(`loaded candidate #${c.rank}`, "ok"); });
      const asB = document.createElement("button");
      asB.type = "button";
      asB.textContent = "B";
      asB.className = "as-b";
      asB.addEventListener("click", () => setB(c.params, `candidate #${c.rank}`));
      td.append(load, asB);
      body.appendChild(tr);
    }
  }

  async function write(path, what) {
    try {
      const doc = await api(path, {params: state.current, label: $("label").value});
      state.lastWrite = doc;
      say(`${what} ${doc.file} (in ${state.session.kind === "run" ? "the run folder" : "the scene's folder"})`, "ok");
    } catch (e) {
      say(e.message, "error");
    }
  }

  async function start() {
    let s;
    try {
      s = await api("/api/session");
    } catch (e) {
      say(e.message, "error");
      return;
    }
    state.session = s;
    document.title = `rvmsim console: ${s.vehicle}`;
    $("title").textContent = s.vehicle;
    $("subtitle").textContent = `${s.description ? s.description + " — " : ""}${s.kind} ${s.source}; criteria ${s.criteria}; ECs at ${s.ec_output.width}×${s.ec_output.height} px; saves into ${s.save_dir}`;
    $("rvm-size").textContent = `(${s.display.width}×${s.display.height} px)`;
    $("fisheye").src = s.fisheye.url;
    $("roi").setAttribute("viewBox", `0 0 ${s.fisheye.width} ${s.fisheye.height}`);
    state.current = {...s.start};
    const box = $("controls");
    for (const spec of s.controls) box.appendChild(buildControl(spec));
    syncControls();
    buildCandidates(s.candidates);
    $("annotate").addEventListener("change", (ev) => { state.annotate = ev.target.checked; request(); });
    $("undo").addEventListener("click", () => {
      if (!state.history.length) { say("nothing to undo", "ok"); return; }
      state.current = state.history.pop();
      syncControls();
      request();
    });
    $("reset").addEventListener("click", () => commit(s.start));
    $("pin").addEventListener("click", () => setB({...state.current}, "pinned setting"));
    $("save").addEventListener("click", () => write("/api/save", "saved"));
    $("report").addEventListener("click", () => write("/api/report", "wrote"));
    document.body.dataset.ready = "1";
    request();
  }

  start();
})();
