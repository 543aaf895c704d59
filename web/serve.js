// dicesim serve: the live run, updated in place from the server-sent events at /events.
(function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
  const dur = (s) => (s >= 3600 ? (s / 3600).toFixed(1) + ' h' : s >= 60 ? (s / 60).toFixed(1) + ' min' : s.toFixed(1) + ' s');
  let bars = [];  // one element per outcome, kept (updated in place)
  function render(state) {
    const r = state.run;
    if (r) {
      $('status').textContent = 'run ' + (r.run_id_text || r.run_id) + (r.finished ? ': finished' : ': running');
      $('status').className = r.finished ? 'finished' : 'running';
      const frac = r.total > 0 ? r.done / r.total : 0;
      $('progress').style.width = (100 * frac).toFixed(2) + '%';
      $('numbers').innerHTML = esc(r.done.toLocaleString('en')) + ' / ' + esc(r.total.toLocaleString('en')) + ' tosses (' +
        (100 * frac).toFixed(1) + ' %) &middot; ' + Math.round(r.tosses_per_s).toLocaleString('en') + ' tosses/s &middot; ' +
        (r.finished ? 'done' : 'ETA ' + dur(r.eta_s)) + ' &middot; ' + r.workers + ' workers &middot; settled ' + r.settled +
        ', unresolved ' + r.unresolved + ', invalid ' + r.invalid;
      if (bars.length !== r.labels.length) {
        $('bars').innerHTML = '';
        bars = r.labels.map(() => {
          const row = document.createElement('div');
          row.className = 'bar';
          row.innerHTML = '<span class="name"></span><span class="track"><span class="fill"></span><span class="ci"></span></span><span class="num"></span>';
          $('bars').appendChild(row);
          return row;
        });
      }
      const top = Math.max(1e-9, ...r.ci_hi);
      r.labels.forEach((label, i) => {
        const row = bars[i];
        row.querySelector('.name').textContent = label;
        row.querySelector('.fill').style.width = (100 * r.p[i] / top) + '%';
        const ci = row.querySelector('.ci');
        ci.style.left = (100 * r.ci_lo[i] / top) + '%';
        ci.style.width = (100 * (r.ci_hi[i] - r.ci_lo[i]) / top) + '%';
        row.querySelector('.num').innerHTML = '<span class="p" data-label="' + label + '">' + r.p[i].toFixed(5) + '</span> [' +
          r.ci_lo[i].toFixed(4) + ', ' + r.ci_hi[i].toFixed(4) + '] <span class="count">' + r.counts[i] + '</span>';
      });
    }
    // What the aggregator rejected (with a run), and what this server heard but could not open:
    // shown with or without a run (a run whose messages all fail the seal never shows one).
    const h = state.heard;
    const rows = r ? [['duplicates', r.duplicates], ['released (lost batches, expired leases)', r.released],
      ['rejected: another run', r.rejected_foreign], ['rejected: malformed', r.rejected_malformed],
      ['rejected: index out of range', r.rejected_range], ['rejected: unauthenticated', r.rejected_unauthenticated]] : [];
    rows.push(['heard here, unauthenticated (seal missing or wrong)', h.unauthenticated, 'heard-unauthenticated'],
      ['heard here, sealed (needs --key-file)', h.sealed, 'heard-sealed'], ['heard here, undecodable', h.malformed, 'heard-malformed']);
    $('health').innerHTML = rows.map((x) => '<tr><td>' + esc(x[0]) + '</td><td' + (x[2] ? ' id="' + x[2] + '"' : '') + '>' + x[1] + '</td></tr>').join('');
    const notes = [];
    if (h.sealed > 0) notes.push(h.sealed + ' messages heard are sealed with a run key, and this server has none: they are not shown (start dicesim serve with --key-file FILE).');
    if (h.unauthenticated > 0) notes.push(h.unauthenticated + ' messages heard failed the HMAC check' +
      (state.key ? ' (sealed with another key, unsealed, or forged)' : '') + ': they are not shown.');
    $('auth').textContent = notes.join(' ');
    $('auth').hidden = notes.length === 0;
    $('workers').innerHTML = '<tr><th>worker</th><th>host</th><th>pid</th><th>state</th><th>tosses</th><th>tosses/s</th><th>last heard</th></tr>' +
      state.workers.map((w) => '<tr><td>' + esc(w.id.toString(16)) + '</td><td>' + esc(w.host) + '</td><td>' + w.pid + '</td><td>' + esc(w.state) +
        (w.error ? ': ' + esc(w.error) : '') + '</td><td>' + w.tosses_done + '</td><td>' + Math.round(w.tosses_per_s) +
        '</td><td class="' + w.health + '">' + w.age_s.toFixed(1) + ' s ago (' + w.health + ')</td></tr>').join('');
  }
  // --trace-every: the latest sampled toss in `dicesim show`'s page (an iframe of /trace), the next
  // one loaded once the one shown has played to its end (or after 20 s).
  let traceShown = null, traceAt = 0;
  function traceIdle() {
    try {
      const play = $('trace-frame').contentDocument.getElementById('play');
      return !play || play.textContent === 'Replay';
    } catch (e) {
      return true;
    }
  }
  function trace(tr) {
    $('trace-box').hidden = !tr;
    if (!tr || tr.index === null) return;
    const want = 'trace?run=' + tr.run + '&index=' + tr.index;
    if (want === traceShown || (traceShown !== null && !traceIdle() && Date.now() - traceAt < 20000)) return;
    traceShown = want;
    traceAt = Date.now();
    $('trace-caption').textContent = '(toss ' + tr.index + ', loading\u2026)';
    $('trace-frame').src = want;
  }
  $('trace-frame').addEventListener('load', () => {
    const d = $('trace-frame').contentDocument;
    if (!d || traceShown === null) return;
    const err = d.getElementById('trace-error'), out = d.getElementById('outcome'), label = d.getElementById('outcome-label');
    const index = (traceShown || '').replace(/.*index=/, '');
    $('trace-caption').innerHTML = err ? '<span id="trace-error">' + esc(err.textContent) + '</span>'
      : '(indices divisible by ' + esc(lastTrace ? lastTrace.every : '?') + '): toss <span id="trace-index">' + esc(index) + '</span>, outcome <span id="trace-outcome">' +
        esc(label ? label.textContent : '?') + '</span>, <span id="trace-clock"></span> <span class="detail">' + esc(out ? out.textContent : '') + '</span>';
  });
  // The toss's clock beside the caption: it runs while the toss plays.
  setInterval(() => {
    let clock = null;
    try { clock = $('trace-frame').contentDocument.getElementById('clock'); } catch (e) { /* not loaded */ }
    const el = document.getElementById('trace-clock');
    if (el && clock) el.textContent = clock.textContent;
    if (lastTrace) trace(lastTrace);  // the next toss, once this one has played (no event comes after a run)
  }, 250);
  let lastTrace = null;
  const source = new EventSource('events');
  source.onmessage = (e) => { const st = JSON.parse(e.data); render(st); lastTrace = st.trace; trace(st.trace); $('conn').textContent = 'connected: updates as the aggregator answers'; };
  source.onerror = () => { $('conn').textContent = 'connection to dicesim serve lost; retrying (the last state stays shown)'; };
})();
