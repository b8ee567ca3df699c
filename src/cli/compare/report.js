// The script of `nimbus compare --html` (html.rs). It runs once, synchronously, at the end of
// <body>: decodes the images from the JSON data block, builds the views, the flip view and the
// charts, and checks itself (body[data-selfcheck]). It loads nothing. Text from the data only
// ever reaches the page through textContent or setAttribute.
(function () {
  'use strict';
  const data = JSON.parse(document.getElementById('nimbus-data').textContent);
  const W = data.reference.width;
  const H = data.reference.height;
  const GALLERY_MAX = 256;
  const FLIP_MAX = [768, 576];

  function decode(b64) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const view = new DataView(bytes.buffer);
    const out = new Float32Array(bytes.length >> 2);
    for (let i = 0; i < out.length; i++) out[i] = view.getFloat32(4 * i, true);
    return out;
  }

  // Index 0 is the reference, 1..n the methods.
  const images = [data.reference].concat(data.methods).map(function (m) {
    return { name: m.name, caption: m.caption, rgb: decode(m.rgb) };
  });
  const n = images.length - 1;
  const ref = images[0].rgb;
  // Per-pixel error of each method: mean over the channels of method - reference.
  const errors = images.slice(1).map(function (m) {
    const e = new Float32Array(W * H);
    for (let p = 0; p < W * H; p++) {
      e[p] = (m.rgb[3 * p] - ref[3 * p] + m.rgb[3 * p + 1] - ref[3 * p + 1] + m.rgb[3 * p + 2] - ref[3 * p + 2]) / 3;
    }
    return e;
  });

  function defaultErrorScale() {
    let sum = 0;
    let count = 0;
    errors.forEach(function (e) {
      for (let p = 0; p < e.length; p++) {
        if (isFinite(e[p])) { sum += e[p] * e[p]; count++; }
      }
    });
    const rms = count ? Math.sqrt(sum / count) : 0;
    return rms > 0 ? 3 * rms : 1;
  }

  const state = {
    exposure: 0, errorScale: defaultErrorScale(), zoom: 1, cx: W / 2, cy: H / 2,
    flip: 0, flipError: false, hover: null,
  };

  // Offscreen canvases at the image's size: tone-mapped images and false-colour errors.
  function offscreen() {
    const c = document.createElement('canvas');
    c.width = W;
    c.height = H;
    return c;
  }
  const imageSources = images.map(offscreen);
  const errorSources = errors.map(offscreen);

  function srgb(v) {
    const s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.round(255 * Math.min(1, Math.max(0, s)));
  }

  // Contexts the self-check reads back (offscreen images, the flip view) are made for reading.
  function context(canvas) { return canvas.getContext('2d', { willReadFrequently: true }); }

  function toneMap(rgb, canvas) {
    const ctx = context(canvas);
    const out = ctx.createImageData(W, H);
    const mul = Math.pow(2, state.exposure);
    for (let p = 0; p < W * H; p++) {
      const r = rgb[3 * p], g = rgb[3 * p + 1], b = rgb[3 * p + 2];
      const bad = !(isFinite(r) && isFinite(g) && isFinite(b));
      out.data[4 * p] = bad ? 255 : srgb(r * mul);
      out.data[4 * p + 1] = bad ? 0 : srgb(g * mul);
      out.data[4 * p + 2] = bad ? 255 : srgb(b * mul);
      out.data[4 * p + 3] = 255;
    }
    ctx.putImageData(out, 0, 0);
  }

  // Green where the method is brighter than the reference, red where darker, black where equal.
  function falseColour(e, canvas) {
    const ctx = context(canvas);
    const out = ctx.createImageData(W, H);
    for (let p = 0; p < W * H; p++) {
      const t = Math.max(-1, Math.min(1, e[p] / state.errorScale));
      const bad = !isFinite(e[p]);
      out.data[4 * p] = bad ? 255 : Math.round(255 * Math.max(0, -t));
      out.data[4 * p + 1] = bad ? 0 : Math.round(255 * Math.max(0, t));
      out.data[4 * p + 2] = bad ? 255 : 0;
      out.data[4 * p + 3] = 255;
    }
    ctx.putImageData(out, 0, 0);
  }

  function renderImages() { images.forEach(function (m, i) { toneMap(m.rgb, imageSources[i]); }); }
  function renderErrors() { errors.forEach(function (e, i) { falseColour(e, errorSources[i]); }); }

  // ---- Views: every canvas shows the same region of the image (zoom and centre are shared).
  const views = [];

  function fitScale(maxW, maxH) {
    const s = Math.min(maxW / W, maxH / H);
    return s >= 1 ? Math.floor(s) : s;
  }

  function addView(canvas, maxW, maxH, source, readBack) {
    const fit = fitScale(maxW, maxH);
    canvas.width = Math.max(1, Math.round(W * fit));
    canvas.height = Math.max(1, Math.round(H * fit));
    const ctx = readBack ? context(canvas) : canvas.getContext('2d');
    const v = { canvas: canvas, ctx: ctx, fit: fit, source: source };
    views.push(v);
    attachMouse(v);
    return v;
  }

  function draw(v) {
    const ctx = v.ctx;
    const cw = v.canvas.width, ch = v.canvas.height;
    const sc = v.fit * state.zoom;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = '#111';
    ctx.fillRect(0, 0, cw, ch);
    ctx.imageSmoothingEnabled = sc < 1;
    ctx.setTransform(sc, 0, 0, sc, cw / 2 - state.cx * sc, ch / 2 - state.cy * sc);
    ctx.drawImage(v.source(), 0, 0);
    if (state.hover && sc >= 3) {
      ctx.strokeStyle = '#00e5ff';
      ctx.lineWidth = 1.5 / sc;
      ctx.strokeRect(state.hover.x, state.hover.y, 1, 1);
    }
    ctx.setTransform(1, 0, 0, 1, 0, 0);
  }

  function drawAll() { views.forEach(draw); }

  // The image point under a mouse event, in pixels of the image (fractional).
  function imagePoint(v, ev) {
    const rect = v.canvas.getBoundingClientRect();
    const mx = (ev.clientX - rect.left) * (v.canvas.width / rect.width);
    const my = (ev.clientY - rect.top) * (v.canvas.height / rect.height);
    const sc = v.fit * state.zoom;
    return { mx: mx, my: my, x: state.cx + (mx - v.canvas.width / 2) / sc, y: state.cy + (my - v.canvas.height / 2) / sc };
  }

  let drag = null;

  function attachMouse(v) {
    const c = v.canvas;
    c.addEventListener('wheel', function (ev) {
      ev.preventDefault();
      const p = imagePoint(v, ev);
      const step = ev.deltaMode === 1 ? 40 : ev.deltaMode === 2 ? 400 : 1;
      state.zoom = Math.min(512, Math.max(0.05, state.zoom * Math.pow(1.0015, -ev.deltaY * step)));
      const sc = v.fit * state.zoom;
      state.cx = p.x - (p.mx - c.width / 2) / sc;
      state.cy = p.y - (p.my - c.height / 2) / sc;
      drawAll();
    }, { passive: false });
    c.addEventListener('mousedown', function (ev) {
      if (ev.button !== 0) return;
      ev.preventDefault();
      drag = { view: v, x: ev.clientX, y: ev.clientY, moved: false };
      c.classList.add('dragging');
    });
    c.addEventListener('mousemove', function (ev) {
      if (drag) return;
      const p = imagePoint(v, ev);
      const x = Math.floor(p.x), y = Math.floor(p.y);
      if (x >= 0 && y >= 0 && x < W && y < H) {
        if (!state.hover || state.hover.x !== x || state.hover.y !== y) {
          state.hover = { x: x, y: y };
          showPixel(x, y);
          drawAll();
        }
      } else if (state.hover) {
        state.hover = null;
        drawAll();
      }
    });
    c.addEventListener('mouseleave', function () {
      if (state.hover && !drag) { state.hover = null; drawAll(); }
    });
  }

  window.addEventListener('mousemove', function (ev) {
    if (!drag) return;
    const rect = drag.view.canvas.getBoundingClientRect();
    const k = drag.view.canvas.width / rect.width;
    const sc = drag.view.fit * state.zoom;
    state.cx -= (ev.clientX - drag.x) * k / sc;
    state.cy -= (ev.clientY - drag.y) * k / sc;
    if (ev.clientX !== drag.x || ev.clientY !== drag.y) drag.moved = true;
    drag.x = ev.clientX;
    drag.y = ev.clientY;
    drawAll();
  });
  window.addEventListener('mouseup', function () {
    if (!drag) return;
    drag.view.canvas.classList.remove('dragging');
    const clicked = drag.view.onClick && !drag.moved ? drag.view.onClick : null;
    drag = null;
    if (clicked) clicked();
  });

  function resetView() {
    state.zoom = 1;
    state.cx = W / 2;
    state.cy = H / 2;
    drawAll();
  }

  // ---- Pixel values under the cursor.
  function fmt(v) { return isFinite(v) ? (Math.abs(v) >= 1e4 || (v !== 0 && Math.abs(v) < 1e-3) ? v.toExponential(3) : v.toPrecision(4)) : String(v); }

  function showPixel(x, y) {
    const panel = document.getElementById('pixel-info');
    panel.textContent = '';
    const head = document.createElement('p');
    head.textContent = 'pixel x ' + x + ', y ' + y;
    panel.appendChild(head);
    const table = document.createElement('table');
    const addRow = function (cells, cls) {
      const tr = document.createElement('tr');
      if (cls) tr.className = cls;
      cells.forEach(function (text, i) {
        const td = document.createElement(cls === 'head' ? 'th' : 'td');
        td.textContent = i === 0 ? text : typeof text === 'number' ? fmt(text) : text;
        tr.appendChild(td);
      });
      table.appendChild(tr);
    };
    addRow(['', 'R', 'G', 'B', 'mean'], 'head');
    const p = 3 * (y * W + x);
    images.forEach(function (m, i) {
      const r = m.rgb[p], g = m.rgb[p + 1], b = m.rgb[p + 2];
      addRow([i + ': ' + m.name, r, g, b, (r + g + b) / 3]);
    });
    images.slice(1).forEach(function (m, i) {
      const d = [m.rgb[p] - ref[p], m.rgb[p + 1] - ref[p + 1], m.rgb[p + 2] - ref[p + 2]];
      addRow(['error ' + (i + 1) + ': ' + m.name, d[0], d[1], d[2], errors[i][y * W + x]], 'error');
    });
    panel.appendChild(table);
  }

  // ---- The gallery: the reference, then each method beside its error.
  function figure(parent, source, kind, index, name, caption, onClick) {
    const fig = document.createElement('figure');
    const canvas = document.createElement('canvas');
    canvas.className = 'view';
    canvas.dataset.kind = kind;
    canvas.dataset.index = String(index);
    fig.appendChild(canvas);
    const cap = document.createElement('figcaption');
    const nameEl = document.createElement('span');
    nameEl.className = 'name';
    const key = document.createElement('span');
    key.className = 'key';
    key.textContent = index <= 9 ? '[' + index + (kind === 'error' ? ' e' : '') + '] ' : '';
    nameEl.appendChild(key);
    nameEl.appendChild(document.createTextNode(name));
    cap.appendChild(nameEl);
    if (caption) cap.appendChild(document.createTextNode(caption));
    fig.appendChild(cap);
    parent.appendChild(fig);
    const v = addView(canvas, GALLERY_MAX, GALLERY_MAX, function () { return source; });
    v.onClick = onClick;
    return v;
  }

  const gallery = document.getElementById('gallery');
  figure(gallery, imageSources[0], 'image', 0, images[0].name, 'what every method is measured against',
    function () { setFlip(0, false); });
  images.slice(1).forEach(function (m, i) {
    const group = document.createElement('div');
    group.className = 'group';
    gallery.appendChild(group);
    figure(group, imageSources[i + 1], 'image', i + 1, m.name, m.caption, function () { setFlip(i + 1, false); });
    figure(group, errorSources[i], 'error', i + 1, m.name + ' − reference', 'green brighter, red darker',
      function () { setFlip(i + 1, true); });
  });

  // ---- The flip view.
  const flipCanvas = document.getElementById('flip');
  const flipButtons = [];
  function flipSource() {
    return state.flip > 0 && state.flipError ? errorSources[state.flip - 1] : imageSources[state.flip];
  }
  const flipView = addView(flipCanvas, FLIP_MAX[0], FLIP_MAX[1], flipSource, true);

  function setFlip(index, error) {
    state.flip = Math.max(0, Math.min(n, index));
    state.flipError = !!error;
    const m = images[state.flip];
    let label = state.flip + ': ' + m.name;
    if (state.flipError) label += state.flip > 0 ? ' — error (method − reference)' : ' (the reference has no error image)';
    document.getElementById('flip-label').textContent = 'shown: ' + label;
    flipCanvas.dataset.shown = String(state.flip);
    flipCanvas.dataset.error = String(state.flipError);
    flipButtons.forEach(function (b, i) { b.classList.toggle('shown', i === state.flip); });
    draw(flipView);
  }

  images.forEach(function (m, i) {
    const b = document.createElement('button');
    b.type = 'button';
    b.textContent = (i <= 9 ? i + ': ' : '') + m.name;
    b.addEventListener('click', function () { setFlip(i, state.flipError); });
    document.getElementById('flip-buttons').appendChild(b);
    flipButtons.push(b);
  });

  // ---- Controls and keys.
  const exposure = document.getElementById('exposure');
  const scaleInput = document.getElementById('error-scale');
  const scaleLog = Math.log10(state.errorScale);
  scaleInput.min = String(scaleLog - 4);
  scaleInput.max = String(scaleLog + 4);
  scaleInput.value = String(scaleLog);

  function setExposure(ev) {
    state.exposure = Math.max(-10, Math.min(10, ev));
    exposure.value = String(state.exposure);
    document.getElementById('exposure-value').textContent = (state.exposure >= 0 ? '+' : '') + state.exposure.toFixed(2) + ' EV';
    renderImages();
    drawAll();
  }
  function setErrorScale(s) {
    state.errorScale = s;
    document.getElementById('error-scale-value').textContent = '±' + s.toPrecision(2);
    renderErrors();
    drawAll();
  }
  exposure.addEventListener('input', function () { setExposure(parseFloat(exposure.value)); });
  scaleInput.addEventListener('input', function () { setErrorScale(Math.pow(10, parseFloat(scaleInput.value))); });
  document.getElementById('reset').addEventListener('click', resetView);

  document.addEventListener('keydown', function (ev) {
    const t = ev.target;
    if (t && (t.tagName === 'TEXTAREA' || t.tagName === 'SELECT' || (t.tagName === 'INPUT' && t.type !== 'range'))) return;
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const k = ev.key;
    if (/^[0-9]$/.test(k)) {
      if (+k <= n) setFlip(+k, state.flipError);
    } else if (k === 'e' || k === 'E') {
      setFlip(state.flip, !state.flipError);
    } else if (k === 'r' || k === 'R') {
      resetView();
    } else if (k === '+' || k === '=') {
      setExposure(state.exposure + 0.5);
    } else if (k === '-' || k === '_') {
      setExposure(state.exposure - 0.5);
    } else {
      return;
    }
    ev.preventDefault();
  });

  // ---- Charts: log-log SVG, a line and markers per series, a legend, the nearest point on hover.
  function tickLabel(v) {
    return v >= 1e-2 && v < 1e4 ? String(+v.toPrecision(3)) : v.toExponential(0);
  }

  function drawChart(svg, chart) {
    const NS = svg.namespaceURI;
    const el = function (name, attrs, parent, text) {
      const e = document.createElementNS(NS, name);
      Object.keys(attrs).forEach(function (k) { e.setAttribute(k, attrs[k]); });
      if (text !== undefined) e.textContent = text;
      parent.appendChild(e);
      return e;
    };
    const CW = 640, CH = 400, L = 72, R = 20, T = 36, B = 52;
    svg.setAttribute('viewBox', '0 0 ' + CW + ' ' + CH);
    svg.setAttribute('width', CW);
    svg.setAttribute('height', CH);
    const all = [];
    chart.series.forEach(function (s) { s.points.forEach(function (p) { all.push(p); }); });
    // Log10 of the axis ends: the data with a margin, at least 0.3 decades.
    const range = function (values) {
      let lo = Math.log10(Math.min.apply(null, values));
      let hi = Math.log10(Math.max.apply(null, values));
      if (hi - lo < 0.3) { const mid = (lo + hi) / 2; lo = mid - 0.15; hi = mid + 0.15; }
      const pad = 0.06 * (hi - lo);
      return [lo - pad, hi + pad];
    };
    const xr = all.length ? range(all.map(function (p) { return p[0]; })) : [0, 1];
    const yr = all.length ? range(all.map(function (p) { return p[1]; })) : [-3, 0];
    const sx = function (x) { return L + (Math.log10(x) - xr[0]) / (xr[1] - xr[0]) * (CW - L - R); };
    const sy = function (y) { return CH - B - (Math.log10(y) - yr[0]) / (yr[1] - yr[0]) * (CH - T - B); };
    const grid = el('g', {}, svg);
    // Grid lines at 1..9 × 10^d inside the range; labels at 10^d, or at 1, 2, 5 × 10^d on a
    // short axis, or at every line when that would leave fewer than two.
    const ticks = function (r, along) {
      const lines = [];
      for (let d = Math.floor(r[0]); d <= Math.ceil(r[1]); d++) {
        for (let m = 1; m <= 9; m++) {
          const v = m * Math.pow(10, d);
          if (Math.log10(v) >= r[0] && Math.log10(v) <= r[1]) lines.push([v, m]);
        }
      }
      let labelled = r[1] - r[0] > 2.5 ? [1] : [1, 2, 5];
      if (lines.filter(function (l) { return labelled.indexOf(l[1]) >= 0; }).length < 2) labelled = [1, 2, 3, 4, 5, 6, 7, 8, 9];
      lines.forEach(function (l) { along(l[0], l[1] === 1, labelled.indexOf(l[1]) >= 0); });
    };
    ticks(xr, function (v, major, label) {
      const x = sx(v);
      el('line', { x1: x, x2: x, y1: T, y2: CH - B, class: major ? 'grid major' : 'grid' }, grid);
      if (label) el('text', { x: x, y: CH - B + 16, 'text-anchor': 'middle' }, svg, tickLabel(v));
    });
    ticks(yr, function (v, major, label) {
      const y = sy(v);
      el('line', { x1: L, x2: CW - R, y1: y, y2: y, class: major ? 'grid major' : 'grid' }, grid);
      if (label) el('text', { x: L - 6, y: y + 4, 'text-anchor': 'end' }, svg, tickLabel(v));
    });
    el('rect', { x: L, y: T, width: CW - L - R, height: CH - T - B, class: 'frame' }, svg);
    el('text', { x: CW / 2, y: 22, 'text-anchor': 'middle', 'font-size': 15, 'font-weight': 600 }, svg, chart.title);
    el('text', { x: L + (CW - L - R) / 2, y: CH - 12, 'text-anchor': 'middle' }, svg, chart.x_label);
    el('text', { x: 16, y: T + (CH - T - B) / 2, 'text-anchor': 'middle',
      transform: 'rotate(-90 16 ' + (T + (CH - T - B) / 2) + ')' }, svg, chart.y_label);
    const marks = [];
    chart.series.forEach(function (s, si) {
      const d = s.points.map(function (p, i) { return (i ? 'L' : 'M') + sx(p[0]).toFixed(2) + ' ' + sy(p[1]).toFixed(2); }).join(' ');
      const path = el('path', { d: d, class: 'series' }, svg);
      path.setAttribute('stroke', s.color);
      path.dataset.series = String(si);
      s.points.forEach(function (p) {
        const c = el('circle', { cx: sx(p[0]), cy: sy(p[1]), r: 3.5, class: 'marker' }, svg);
        c.setAttribute('fill', s.color);
        marks.push({ x: sx(p[0]), y: sy(p[1]), series: s.name, t: p[0], e: p[1] });
      });
    });
    const legend = el('g', {}, svg);
    chart.series.forEach(function (s, i) {
      const y = T + 14 + 18 * i;
      el('line', { x1: CW - R - 150, x2: CW - R - 126, y1: y, y2: y, 'stroke-width': 2 }, legend).setAttribute('stroke', s.color);
      el('text', { x: CW - R - 120, y: y + 4 }, legend, s.name);
    });
    const bbox = el('rect', { x: CW - R - 158, y: T + 4, width: 154, height: 18 * chart.series.length + 4,
      fill: 'white', 'fill-opacity': 0.85, stroke: '#999' }, legend);
    legend.insertBefore(bbox, legend.firstChild);
    const ring = el('circle', { r: 7, class: 'highlight', visibility: 'hidden' }, svg);
    const tip = svg.parentNode.querySelector('.tooltip');
    svg.addEventListener('mousemove', function (ev) {
      const rect = svg.getBoundingClientRect();
      const mx = (ev.clientX - rect.left) * CW / rect.width, my = (ev.clientY - rect.top) * CH / rect.height;
      let best = null, bestD = 30 * 30;
      marks.forEach(function (m) {
        const d = (m.x - mx) * (m.x - mx) + (m.y - my) * (m.y - my);
        if (d < bestD) { bestD = d; best = m; }
      });
      if (!best) { tip.hidden = true; ring.setAttribute('visibility', 'hidden'); return; }
      ring.setAttribute('cx', best.x);
      ring.setAttribute('cy', best.y);
      ring.setAttribute('visibility', 'visible');
      tip.textContent = best.series + ': ' + fmt(best.t) + ' s, ' + chart.y_label + ' ' + best.e.toExponential(3);
      tip.hidden = false;
      tip.style.left = (best.x * rect.width / CW + 10) + 'px';
      tip.style.top = (best.y * rect.height / CH - 28) + 'px';
    });
    svg.addEventListener('mouseleave', function () { tip.hidden = true; ring.setAttribute('visibility', 'hidden'); });
  }

  document.querySelectorAll('svg.chart-svg').forEach(function (svg) {
    drawChart(svg, data.charts[+svg.dataset.chart]);
  });

  // ---- First paint.
  setExposure(0);
  setErrorScale(state.errorScale);
  setFlip(0, false);

  // ---- The self-check.
  function checksum(canvas) {
    const d = context(canvas).getImageData(0, 0, canvas.width, canvas.height).data;
    let h = 2166136261;
    for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
    return h >>> 0;
  }

  function press(key) {
    document.dispatchEvent(new KeyboardEvent('keydown', { key: key, bubbles: true, cancelable: true }));
  }

  function selfCheck() {
    const problems = [];
    const imageViews = gallery.querySelectorAll('canvas.view[data-kind="image"]').length;
    const errorViews = gallery.querySelectorAll('canvas.view[data-kind="error"]').length;
    if (imageViews !== n + 1) problems.push(imageViews + ' image views for ' + (n + 1) + ' images');
    if (errorViews !== n) problems.push(errorViews + ' error views for ' + n + ' methods');
    images.forEach(function (m) {
      if (m.rgb.length !== W * H * 3) problems.push(m.name + ' decodes to ' + m.rgb.length + ' floats, not ' + W * H * 3);
    });
    if (n >= 1) {
      const sources = imageSources.map(checksum);
      const errorSums = errorSources.map(checksum);
      const step = function (key, index, error, sourceSum, before) {
        press(key);
        const now = checksum(flipCanvas);
        if (state.flip !== index || state.flipError !== error || flipCanvas.dataset.shown !== String(index)) {
          problems.push('key ' + key + ' shows ' + state.flip + (state.flipError ? 'e' : '') + ', not ' + index + (error ? 'e' : ''));
        } else if (sourceSum !== before.source && now === before.shown) {
          problems.push('key ' + key + ' left the flip view\'s pixels unchanged');
        }
        return { shown: now, source: sourceSum };
      };
      setFlip(0, false);
      let last = { shown: checksum(flipCanvas), source: sources[0] };
      last = step('1', 1, false, sources[1], last);
      last = step('e', 1, true, errorSums[0], last);
      last = step('e', 1, false, sources[1], last);
      const second = n >= 2 ? 2 : 0;
      step(String(second), second, false, sources[second], last);
      setFlip(0, false);
    }
    document.querySelectorAll('svg.chart-svg').forEach(function (svg) {
      const chart = data.charts[+svg.dataset.chart];
      const paths = svg.querySelectorAll('path.series').length;
      if (paths !== chart.series.length) problems.push('chart "' + chart.title + '" has ' + paths + ' paths for ' + chart.series.length + ' series');
    });
    if (document.querySelectorAll('svg.chart-svg').length !== data.charts.length) problems.push('a chart is missing');
    window.__nimbusErrors.forEach(function (e) { problems.push('error: ' + e); });
    const verdict = problems.length ? 'fail: ' + problems.join('; ') : 'pass';
    document.body.dataset.selfcheck = verdict;
    const status = document.getElementById('selfcheck-status');
    status.textContent = 'self-check: ' + verdict;
    status.classList.toggle('fail', problems.length > 0);
  }

  selfCheck();
})();
