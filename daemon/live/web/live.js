// live.js: the live page's behaviour (docs/live-page.md). Follows ribbond's event stream
// (GET /live/events, read with fetch so the token can travel in the Authorization header),
// draws the measured points against the prediction with Chart.js, refreshes the camera picture
// and the phase diagram, lists the trials with links to their report and samples CSV, shows the
// campaign's queue with the form of the operator step it waits for, and calls the existing API for
// start and abort, the queue's start and stop and the step's confirmation: the page has no power
// the API does not have. A replay
// (replay mode) is followed the same way: it publishes what a trial does.
'use strict';

const $ = (id) => document.getElementById(id);
const TOKEN_KEY = 'ribbon-token';
let token = sessionStorage.getItem(TOKEN_KEY) || '';
let tokenWaiters = [];

// ---- the API, with the token when this ribbond needs one ------------------------------------
function askToken() {
  $('token-form').hidden = false;
  $('token').focus();
  return new Promise((resolve) => tokenWaiters.push(resolve));
}
$('token-form').addEventListener('submit', (e) => {
  e.preventDefault();
  token = $('token').value.trim();
  sessionStorage.setItem(TOKEN_KEY, token);
  $('token-form').hidden = true;
  const w = tokenWaiters;
  tokenWaiters = [];
  w.forEach((r) => r());
});

async function api(path, opts = {}) {
  for (;;) {
    const headers = Object.assign({}, opts.headers || {});
    if (token) headers['Authorization'] = 'Bearer ' + token;
    const r = await fetch(path, Object.assign({}, opts, { headers, cache: 'no-store' }));
    if (r.status !== 401) return r;
    await askToken();
  }
}

// ---- numbers --------------------------------------------------------------------------------
const fmt = (v, d = 5) => (v === null || v === undefined || Number.isNaN(v) ? '-' : Number(v).toFixed(d));
function setNum(id, v, d) {
  const e = $(id);
  e.textContent = fmt(v, d);
  e.dataset.value = v === null || v === undefined ? '' : String(v);
}

let view = null;
let daemonMode = null; // from GET /status: a replay-mode daemon has no queue, and is not asked
function resetView(trial) {
  view = { trial, samples: 0, frames: 0, measured: 0, missed: 0, haveFrame: false, predSnap: null, measSnap: null,
    calSnap: null, calSd: null };
  $('trial-id').textContent = trial === null ? '-' : String(trial);
  for (const id of ['v-dl', 'v-dw', 'v-dz', 'v-a', 'v-q', 'v-t', 'snap-predicted', 'snap-measured', 'snap-calibrated',
    'snap-calibrated-sd']) setNum(id, null);
  $('regime-calibrated').textContent = '-';
  $('calibration-fit').textContent = '-';
  for (const id of ['v-samples', 'v-frames', 'v-measured', 'v-unmeasured', 'v-missed', 'v-dropped', 'v-skipped'])
    $(id).textContent = '0';
  view.dropped = 0;
  view.skipped = 0;
  $('regime-predicted').textContent = '-';
  $('regime-measured').textContent = '-';
  $('events').textContent = '';
  for (const c of charts) {
    c.data.datasets.forEach((ds) => (ds.data = []));
  }
  dirty = true;
}

function setState(s) {
  $('state').textContent = s;
  $('v-state').textContent = s;
  $('state').dataset.state = s;
  const seen = ($('state').dataset.seen || '').split(' ').filter((x) => x);
  if (!seen.includes(s)) seen.push(s);
  $('state').dataset.seen = seen.join(' ');
}

// ---- plots ------------------------------------------------------------------------------------
const charts = [];
let dirty = false;
function makeChart(canvas, ylabel) {
  if (typeof Chart === 'undefined') return null;
  return new Chart($(canvas), {
    type: 'scatter',
    data: {
      datasets: [
        { label: 'measured', data: [], pointRadius: 2, backgroundColor: '#1565c0', borderColor: '#1565c0' },
        { label: 'predicted', data: [], showLine: true, pointRadius: 0, borderWidth: 2, borderColor: '#ef6c00' },
        { label: 'predicted snap', data: [], showLine: true, pointRadius: 0, borderDash: [6, 4], borderColor: '#ef6c00' },
        { label: 'measured snap', data: [], showLine: true, pointRadius: 0, borderDash: [2, 2], borderColor: '#1565c0' },
        // The calibrated prediction (issue 32 B): its snap, and its 1-sigma band as a shaded
        // rectangle (a closed outline filled to itself).
        { label: 'calibrated snap', data: [], showLine: true, pointRadius: 0, borderDash: [4, 2], borderColor: '#00896a' },
        { label: 'calibrated band (1\u03c3)', data: [], showLine: true, pointRadius: 0, borderWidth: 0,
          backgroundColor: 'rgba(0, 137, 106, 0.18)', fill: true },
      ],
    },
    options: {
      animation: false, maintainAspectRatio: false, parsing: false, normalized: true,
      scales: { x: { title: { display: true, text: '\u0394W' } }, y: { title: { display: true, text: ylabel } } },
    },
  });
}
function markSnaps() {
  for (const c of charts) {
    const ys = c.data.datasets[0].data.concat(c.data.datasets[1].data).map((p) => p.y);
    if (ys.length === 0) continue;
    const lo = Math.min(...ys), hi = Math.max(...ys);
    c.data.datasets[2].data = view && view.predSnap !== null ? [{ x: view.predSnap, y: lo }, { x: view.predSnap, y: hi }] : [];
    c.data.datasets[3].data = view && view.measSnap !== null ? [{ x: view.measSnap, y: lo }, { x: view.measSnap, y: hi }] : [];
    const cs = view ? view.calSnap : null, sd = view ? view.calSd : null;
    c.data.datasets[4].data = cs !== null ? [{ x: cs, y: lo }, { x: cs, y: hi }] : [];
    c.data.datasets[5].data = cs !== null && sd !== null && sd > 0
      ? [{ x: cs - sd, y: lo }, { x: cs - sd, y: hi }, { x: cs + sd, y: hi }, { x: cs + sd, y: lo }, { x: cs - sd, y: lo }] : [];
  }
}
setInterval(() => {
  if (!dirty) return;
  dirty = false;
  markSnaps();
  charts.forEach((c) => c.update('none'));
  const n = charts.length ? charts[0].data.datasets[0].data.length : 0;
  $('plot-dz').dataset.points = String(n);
  $('plot-dz').dataset.predicted = String(charts.length ? charts[0].data.datasets[1].data.length : 0);
}, 250);

// ---- messages ---------------------------------------------------------------------------------
function addEvent(m) {
  const li = document.createElement('li');
  li.className = m.kind || '';
  li.textContent = (m.t === null || m.t === undefined ? '' : fmt(m.t, 2) + ' s  ') + (m.kind ? m.kind + ': ' : '') + m.message;
  $('events').appendChild(li);
  $('events').scrollTop = $('events').scrollHeight;
}

async function loadPrediction(trial) {
  const r = await api('/live/prediction');
  if (!r.ok) return;
  const p = await r.json();
  if (!view || p.trial !== view.trial || !charts.length) return;
  const zs = [], as = [];
  for (let i = 0; i < p.dw.length; i++) {
    if (p.dz[i] !== null) zs.push({ x: p.dw[i], y: p.dz[i] });
    if (p.a[i] !== null) as.push({ x: p.dw[i], y: p.a[i] });
  }
  charts[0].data.datasets[1].data = zs;
  charts[1].data.datasets[1].data = as;
  dirty = true;
}

function handle(m) {
  switch (m.type) {
    case 'hello': resetView(null); break;
    case 'trial': resetView(m.trial); setState('created'); $('mode').textContent = '(' + m.mode + ')'; break;
    case 'gap': view.missed += m.missed; $('v-missed').textContent = String(view.missed); break;
    case 'state': if (!view || view.trial !== m.trial) resetView(m.trial); setState(m.state); break;
    case 'event': addEvent(m); break;
    case 'sample':
      if (!view || view.trial !== m.trial) resetView(m.trial);
      view.samples++;
      $('v-samples').textContent = String(view.samples);
      setNum('v-dl', m.dl); setNum('v-dw', m.dw); setNum('v-t', m.t, 2);
      if (m.kind === 'frame') {
        view.frames++;
        view.haveFrame = true;
        $('v-frames').textContent = String(view.frames);
        $('v-unmeasured').textContent = String(view.frames - view.measured - (m.measured ? 1 : 0));
        setNum('v-q', m.quality, 3);
        if (m.untracked === 'dropped') $('v-dropped').textContent = String(++view.dropped);
        if (m.untracked === 'skipped') $('v-skipped').textContent = String(++view.skipped);
        if (m.measured) {
          view.measured++;
          $('v-measured').textContent = String(view.measured);
          setNum('v-dz', m.dz); setNum('v-a', m.a);
          if (charts.length) {
            charts[0].data.datasets[0].data.push({ x: m.dw, y: m.dz });
            charts[1].data.datasets[0].data.push({ x: m.dw, y: m.a });
            dirty = true;
          }
        }
      }
      break;
    case 'prediction':
      if (!view || view.trial !== m.trial) resetView(m.trial);
      if (m.ok) {
        view.predSnap = m.snapped ? m.snap_dw : null;
        setNum('snap-predicted', m.snapped ? m.snap_dw : null);
        $('regime-predicted').textContent = m.regime;
        loadPrediction(m.trial).catch(() => {});
      } else {
        $('regime-predicted').textContent = 'failed';
      }
      dirty = true;
      break;
    case 'calibrated': // a calibrated prediction landed: the band narrows toward the snap
      if (!view || view.trial !== m.trial) resetView(m.trial);
      $('calibration-fit').textContent = (m.refresh ? 'refresh ' + m.refresh : 'from the hold') + (m.ok ? '' : ': ' + m.why);
      if (m.ok) {
        view.calSnap = m.snapped ? m.snap_dw : null;
        view.calSd = m.snapped ? m.snap_sd : null;
        setNum('snap-calibrated', view.calSnap);
        setNum('snap-calibrated-sd', view.calSd);
        $('regime-calibrated').textContent = m.regime;
      } else if (view.calSnap === null) {
        $('regime-calibrated').textContent = 'failed';
      }
      dirty = true;
      break;
    case 'result':
      view.measSnap = m.snapped ? m.snap_dw : null;
      setNum('snap-measured', m.snapped ? m.snap_dw : null);
      $('regime-measured').textContent = m.regime;
      dirty = true;
      break;
    case 'stored': // the store has the trial's end: the table and the phase diagram show it
      lastStored = m.trial;
      loadTrials().catch(() => {});
      loadPhase().catch(() => {});
      break;
    default: break;
  }
}

// ---- the stream, reconnecting -----------------------------------------------------------------
function setLink(up, text) {
  $('link').className = 'link ' + (up ? 'up' : 'down');
  $('link').textContent = text;
  $('link').dataset.up = up ? '1' : '0';
  if (!up) $('link').dataset.wasDown = '1';
}

async function follow() {
  for (;;) {
    try {
      const r = await api('/live/events');
      if (!r.ok || !r.body) throw new Error('events: HTTP ' + r.status);
      setLink(true, 'live');
      loadStatus().catch(() => {});
      loadTrials().catch(() => {});
      loadPhase().catch(() => {});
      const reader = r.body.getReader();
      const dec = new TextDecoder();
      let buf = '';
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buf += dec.decode(value, { stream: true });
        let k;
        while ((k = buf.indexOf('\n\n')) >= 0) {
          const block = buf.slice(0, k);
          buf = buf.slice(k + 2);
          const data = block.split('\n').filter((l) => l.startsWith('data: ')).map((l) => l.slice(6)).join('\n');
          if (data) handle(JSON.parse(data));
        }
      }
    } catch (e) {
      /* ribbond gone or restarting: said on the page, tried again */
    }
    setLink(false, 'ribbond unreachable, retrying');
    await new Promise((res) => setTimeout(res, 1000));
  }
}

async function loadStatus() {
  const r = await api('/status');
  if (!r.ok) return;
  const s = await r.json();
  $('mode').textContent = '(' + s.mode + ')';
  daemonMode = s.mode;
  $('source-box').hidden = s.mode !== 'replay'; // replay mode: POST /trials {"source_trial": ID}
  $('overrides').disabled = s.mode === 'replay';
  if (s.state === 'idle' && (!view || view.trial === null)) setState('idle');
  showChecks(s.checks);
}

// The rig's readiness checks (GET /status "checks"): the fails and warnings, shown while any
// stands; trials are refused while one fails. "Check again" runs them (POST /checks).
function showChecks(c) {
  if (!c) return;
  const items = (c.checks || []).filter((it) => it.level !== 'ok');
  $('checks-box').hidden = items.length === 0;
  $('checks-state').textContent = c.ok ? 'ready' : 'NOT READY, trials refused';
  $('checks-box').dataset.ok = c.ok ? '1' : '0';
  const ul = $('checks');
  ul.textContent = '';
  for (const it of items) {
    const li = document.createElement('li');
    li.className = it.level === 'fail' ? 'fault' : 'warning';
    li.textContent = it.level + ' ' + it.part + ' ' + it.what + ': ' + it.text;
    ul.appendChild(li);
  }
}

async function loadTrials() {
  const r = await api('/trials');
  if (!r.ok) return;
  const list = await r.json();
  const body = $('trials').tBodies[0];
  body.textContent = '';
  for (const t of list.slice(-30).reverse()) {
    const tr = body.insertRow();
    const cells = [t.id, t.status, fmt(t.snap_dw_measured), t.regime_measured || '-', fmt(t.snap_dw_predicted),
      t.regime_predicted || '-'];
    for (const c of cells) tr.insertCell().textContent = String(c);
    // Links open in the browser, which cannot send the token: beyond loopback they are fetched
    // with it (authedLink) and handed over as a blob.
    tr.insertCell().appendChild(authedLink('/trials/' + t.id + '/report.png', 'PNG', 'report-' + t.id, null));
    tr.insertCell().appendChild(authedLink('/trials/' + t.id + '/samples.csv', 'CSV', 'csv-' + t.id,
      'trial-' + t.id + '-samples.csv'));
  }
}

// A link to an API route: a plain href on a ribbond that needs no token; with a token the click
// fetches the route with it and opens (or saves, with a file name) what came back.
function authedLink(path, text, id, filename) {
  const a = document.createElement('a');
  a.href = path;
  a.id = id;
  a.textContent = text;
  if (filename) a.download = filename;
  a.addEventListener('click', async (e) => {
    if (!token) return;
    e.preventDefault();
    const r = await api(path);
    if (!r.ok) return;
    const url = URL.createObjectURL(await r.blob());
    const b = document.createElement('a');
    b.href = url;
    if (filename) b.download = filename;
    else b.target = '_blank';
    b.click();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
  });
  return a;
}

// ---- the phase diagram: ribbond's phase report, fetched again after each trial and while its
// predicted map is still being computed (X-Phase-Map says how far) ------------------------------
let phaseUrl = null, phaseCount = 0, phaseTimer = null, lastStored = null;
async function loadPhase() {
  clearTimeout(phaseTimer);
  const stored = lastStored; // the last trial the store had finished when this was asked for
  const r = await api('/phase.png');
  if (!r.ok) return;
  const map = r.headers.get('X-Phase-Map') || '-';
  const url = URL.createObjectURL(await r.blob());
  $('phase').src = url;
  if (phaseUrl) URL.revokeObjectURL(phaseUrl);
  phaseUrl = url;
  phaseCount++;
  $('phase').dataset.updates = String(phaseCount);
  $('phase').dataset.map = map;
  $('phase').dataset.trial = stored === null ? '' : String(stored);
  $('phase-info').textContent = 'predicted map: ' + map;
  if (map.startsWith('computing') || map === 'not started') phaseTimer = setTimeout(() => loadPhase().catch(() => {}), 3000);
}

// ---- the lab's phase diagram (GET /campaign/phase) and the planner's proposals (GET /plan,
// POST /plan/ID/approve): loaded at start, after each trial and every 15 s ----------------------
let campaignChart = null;
function campaignPlot(d) {
  if (typeof Chart === 'undefined') return;
  const asym = [], sym = [], other = [], est = [], bars = [], pred = [];
  for (const p of d.points) {
    if (p.n_asym) asym.push({ x: p.gamma, y: p.phi_deg, n: p.n_asym });
    if (p.n_sym) sym.push({ x: p.gamma, y: p.phi_deg, n: p.n_sym });
    if (p.n_other) other.push({ x: p.gamma, y: p.phi_deg, n: p.n_other });
  }
  for (const e of d.edges) {
    if (e.gamma !== null) est.push({ x: e.gamma, y: e.phi_deg });
    if (e.lo !== null || e.hi !== null) {
      bars.push({ x: e.lo !== null ? e.lo : e.hi, y: e.phi_deg }, { x: e.hi !== null ? e.hi : e.lo, y: e.phi_deg }, { x: NaN, y: NaN });
    }
  }
  if (d.predicted) d.predicted.phi_deg.forEach((phi, k) => pred.push({ x: d.predicted.gamma[k], y: phi }));
  const sets = [
    { label: 'measured asymmetric', data: asym, pointStyle: 'rect', pointRadius: 6, backgroundColor: '#0d3b8c' },
    { label: 'measured symmetric', data: sym, pointStyle: 'circle', pointRadius: 6, backgroundColor: 'rgba(0,0,0,0)', borderColor: '#a11d1d', borderWidth: 2 },
    { label: 'no snap / unknown', data: other, pointStyle: 'crossRot', pointRadius: 6, borderColor: '#555' },
    { label: 'experimental boundary', data: est, pointStyle: 'star', pointRadius: 8, borderColor: '#009e73', showLine: true, borderWidth: 2 },
    { label: 'its interval', data: bars, showLine: true, pointRadius: 0, borderWidth: 5, borderColor: '#009e73', spanGaps: false },
    { label: 'predicted boundary', data: pred, showLine: true, pointRadius: 0, borderDash: [6, 4], borderColor: '#000' },
  ];
  if (!campaignChart) {
    campaignChart = new Chart($('campaign-plot'), {
      type: 'scatter',
      data: { datasets: sets },
      options: {
        animation: false, maintainAspectRatio: false, parsing: false,
        scales: { x: { title: { display: true, text: '\u0393' } }, y: { title: { display: true, text: '\u03c6 (deg)' } } },
        plugins: { tooltip: { callbacks: { label: (c) => `${c.dataset.label}: \u0393 ${c.raw.x}, \u03c6 ${c.raw.y}` + (c.raw.n > 1 ? ` (\u00d7${c.raw.n})` : '') } } },
      },
    });
  } else {
    campaignChart.data.datasets = sets;
    campaignChart.update();
  }
}
async function loadCampaign() {
  const r = await api('/campaign/phase');
  const d = await r.json().catch(() => ({}));
  $('campaign-box').dataset.status = String(r.status);
  if (r.status === 503) {
    // the predicted boundary is being traced in the background: ask again when the daemon says
    const s = Math.min(Math.max(Number(r.headers.get('Retry-After')) || 1, 1), 15);
    setTimeout(() => loadCampaign().catch(() => {}), 1000 * s);
  }
  if (!r.ok || d.empty) {
    $('campaign-info').textContent = d.empty || d.error || ('HTTP ' + r.status);
  } else {
    $('campaign-info').textContent = `${d.specimens} specimens, ${d.trials} measured trials; predicted boundary: ` +
      (d.predicted ? d.predicted.source : (d.predicted_error || 'none'));
    const tb = $('edges').tBodies[0];
    tb.replaceChildren();
    for (const e of d.edges) {
      const tr = tb.insertRow();
      for (const t of [e.phi_deg, e.method, fmt(e.gamma, 4), `[${fmt(e.lo, 4)}, ${fmt(e.hi, 4)}]`, e.n_asym, e.n_sym, fmt(e.predicted_gamma, 4)])
        tr.insertCell().textContent = String(t);
    }
    $('edges').dataset.rows = String(d.edges.length);
    campaignPlot(d);
  }
  const pr = await api('/plan');
  if (!pr.ok) return;
  const list = await pr.json();
  const tb = $('proposals').tBodies[0];
  tb.replaceChildren();
  for (const p of list.slice(0, 12)) {
    const tr = tb.insertRow();
    for (const t of [p.id, p.status, p.phi_deg, fmt(p.gamma, 4), fmt(p.sd_before, 4), fmt(p.offset_mean, 4), p.specimen || '-'])
      tr.insertCell().textContent = String(t);
    const cell = tr.insertCell();
    if (p.status === 'proposed') {
      const b = document.createElement('button');
      b.type = 'button';
      b.textContent = 'Approve';
      b.addEventListener('click', async () => {
        const a = await api(`/plan/${p.id}/approve`, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{}' });
        const j = await a.json().catch(() => ({}));
        $('proposal-msg').textContent = a.ok ? `proposal ${p.id} queued: specimen ${j.proposal.specimen}` : 'refused (' + a.status + '): ' + (j.error || '');
        $('proposal-msg').dataset.status = String(a.status);
        loadCampaign().catch(() => {});
        loadQueue().catch(() => {});
      });
      cell.appendChild(b);
    }
  }
}

// ---- camera -----------------------------------------------------------------------------------
let camUrl = null, camCount = 0;
async function camera() {
  for (;;) {
    await new Promise((res) => setTimeout(res, 200));
    if (!view || !view.haveFrame || document.hidden) continue;
    try {
      const r = await api('/live/camera.jpg');
      if (!r.ok) continue;
      const blob = await r.blob();
      const url = URL.createObjectURL(blob);
      $('camera').src = url;
      if (camUrl) URL.revokeObjectURL(camUrl);
      camUrl = url;
      camCount++;
      $('camera').dataset.updates = String(camCount);
      $('camera-info').textContent = camCount + ' pictures';
    } catch (e) {
      /* unreachable: the stream's loop says so */
    }
  }
}

// ---- controls ---------------------------------------------------------------------------------
async function control(path, body) {
  const r = await api(path, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
  const j = await r.json().catch(() => ({}));
  $('control-msg').textContent = r.ok ? path + ': ' + (j.abort || j.status || 'ok') : 'refused (' + r.status + '): ' + (j.error || '');
  $('control-msg').dataset.status = String(r.status);
}
$('start').addEventListener('click', () => {
  const body = {};
  const note = $('note').value.trim();
  if (note) body.note = note;
  const set = $('overrides').value.split('\n').map((l) => l.trim()).filter((l) => l);
  if (set.length && !$('overrides').disabled) body.set = set;
  const source = parseInt($('source').value, 10);
  if (!$('source-box').hidden && source >= 1) body.source_trial = source;
  control('/trials', body).catch((e) => ($('control-msg').textContent = String(e)));
});
$('checks-run').addEventListener('click', () => control('/checks', {}).then(loadStatus).catch((e) => ($('control-msg').textContent = String(e))));
$('abort').addEventListener('click', () => control('/trials/current/abort', {}).catch((e) => ($('control-msg').textContent = String(e))));

// ---- the campaign's queue (docs/campaign.md) ----------------------------------------------------
// GET /queue once a second: its state, the running item, the queued ones and the latest ended;
// the operator step the queue waits for gets a form of its fields, sent to POST /queue/ID/confirm.
let opShown = null; // the operator step whose form is shown (kept while the operator types)
async function loadQueue() {
  if (daemonMode === null || daemonMode === 'replay') {
    $('queue-box').hidden = true;
    return;
  }
  const r = await api('/queue');
  if (!r.ok) {
    $('queue-box').hidden = true;
    return;
  }
  const q = await r.json();
  $('queue-box').hidden = false;
  $('queue-state').textContent = q.running ? 'running' : 'stopped';
  $('queue-state').dataset.running = q.running ? '1' : '0';
  $('queue-reason').textContent = q.running ? '' : q.reason || '';
  const body = $('queue').tBodies[0];
  body.textContent = '';
  const rows = [].concat(q.current ? [q.current] : [], q.queued || [], (q.history || []).slice(0, 20));
  for (const it of rows) {
    const tr = body.insertRow();
    tr.dataset.id = String(it.id);
    tr.dataset.status = it.status;
    const what = it.kind === 'trial' ? (it.specimen || '') + (it.note ? ' (' + it.note + ')' : '')
      : it.kind === 'operator' ? it.prompt || '' : it.note || '';
    for (const c of [it.id, it.status, it.kind, what, it.trial_id || '-', it.reason || ''])
      tr.insertCell().textContent = String(c);
  }
  const op = q.current && q.current.kind === 'operator' ? q.current : null;
  if (!op) {
    $('operator-form').hidden = true;
    opShown = null;
    return;
  }
  if (opShown === op.id) return;
  opShown = op.id;
  $('operator-prompt').textContent = 'Step ' + op.id + ': ' + (op.prompt || '') + (op.specimen ? ' (' + op.specimen + ')' : '');
  const box = $('operator-fields');
  box.textContent = '';
  for (const f of op.fields || []) {
    const l = document.createElement('label');
    l.textContent = f + ' ';
    const i = document.createElement('input');
    i.name = f;
    i.id = 'field-' + f;
    i.type = 'text';
    l.appendChild(i);
    box.appendChild(l);
  }
  $('operator-msg').textContent = '';
  delete $('operator-msg').dataset.status;
  $('operator-form').hidden = false;
}
$('operator-form').addEventListener('submit', async (e) => {
  e.preventDefault();
  const values = {};
  for (const i of $('operator-fields').querySelectorAll('input')) {
    const v = i.value.trim();
    values[i.name] = i.name === 'folded_at' || v === '' || Number.isNaN(Number(v)) ? v : Number(v);
  }
  const r = await api('/queue/' + opShown + '/confirm',
    { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ values }) });
  const j = await r.json().catch(() => ({}));
  $('operator-msg').textContent = r.ok ? 'confirmed' : 'refused (' + r.status + '): ' + (j.error || '');
  $('operator-msg').dataset.status = String(r.status);
  if (r.ok) loadQueue().catch(() => {});
});
$('queue-start').addEventListener('click', () => control('/queue/start', {}).then(loadQueue).catch((e) => ($('control-msg').textContent = String(e))));
$('queue-stop').addEventListener('click', () => control('/queue/stop', {}).then(loadQueue).catch((e) => ($('control-msg').textContent = String(e))));
setInterval(() => loadQueue().catch(() => {}), 1000);

// ---- start ------------------------------------------------------------------------------------
const c1 = makeChart('plot-dz', '\u0394Z'), c2 = makeChart('plot-a', 'A (rad)');
if (c1 && c2) charts.push(c1, c2);
else $('control-msg').textContent = 'Chart.js is missing (install libjs-chart.js): no plots';
resetView(null);
loadCampaign().catch(() => {});
setInterval(() => loadCampaign().catch(() => {}), 15000);
follow();
camera();
