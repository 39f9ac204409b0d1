// tightex's report page: fills the tables from report.json, draws the atlases and the density heat
// map, and shows both models in two linked three.js views. Everything it reads is in the page
// (report-json, model-data); it fetches nothing.
'use strict';
(function () {
  // The page's state for a test driver: ready once the viewer has drawn; errors met on the way.
  const state = { ready: false, errors: [] };
  window.tightexPage = state;

  function showError(message) {
    state.errors.push(String(message));
    const box = document.getElementById('errors');
    box.textContent = 'This page met an error: ' + state.errors.join('; ');
    box.classList.add('shown');
  }
  window.addEventListener('error', (e) => showError(e.message));
  window.addEventListener('unhandledrejection', (e) => showError(e.reason));

  const report = JSON.parse(document.getElementById('report-json').textContent);
  const modelData = JSON.parse(document.getElementById('model-data').textContent);

  // ------------------------------------------------------------------------------------------------
  // Numbers and cells

  function get(path) {
    return path.split('.').reduce((v, k) => (v === undefined || v === null ? undefined : v[k]), report);
  }

  // `value` with `digits` decimals and thousands separators; digits 'sig3': three significant digits
  // (areas of components from a few triangles to the whole model).
  function formatNumber(value, digits) {
    if (digits === 'sig3') return value === 0 ? '0' : String(Number(value.toPrecision(3)));
    return value.toLocaleString('en-US', { minimumFractionDigits: digits, maximumFractionDigits: digits });
  }

  function el(tag, attrs, children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === 'text') e.textContent = v;
      else if (k === 'class') e.className = v;
      else e.setAttribute(k, v);
    }
    for (const c of children || []) e.append(c);
    return e;
  }

  // A number from report.json, shown scaled and rounded, with the key it came from (data-key) so that
  // a reader or a test can check it against the file.
  function reportNumber(path, digits, scale, unit) {
    const value = get(path);
    if (typeof value !== 'number') return document.createTextNode('\u2014');
    const s = scale || 1;
    const span = el('span', { class: 'num', 'data-key': path, 'data-scale': String(s), text: formatNumber(value * s, digits) });
    if (digits === 'sig3') span.dataset.precision = 'sig3';
    const wrap = el('span', {}, [span]);
    if (unit) wrap.append(unit);
    return wrap;
  }

  function joined(parts, separator) {
    const wrap = el('span');
    parts.forEach((p, i) => {
      if (i > 0) wrap.append(separator);
      wrap.append(p);
    });
    return wrap;
  }

  // ------------------------------------------------------------------------------------------------
  // Summary

  // "1024 × 1024", or for several pages "3 × (1024 × 1024), 512 × 512" (equal sizes counted).
  function textureSizes(model) {
    if (!model.textures.length) return 'none';
    const counts = new Map();
    for (const t of model.textures) {
      const size = t.width + ' \u00d7 ' + t.height;
      counts.set(size, (counts.get(size) || 0) + 1);
    }
    return Array.from(counts, ([size, n]) => (n > 1 ? n + ' \u00d7 (' + size + ')' : size)).join(', ');
  }

  // Every written image in one line each: file, size, codec and quality, bytes, the written figure of each slot it serves.
  function writtenImages() {
    const figure = (v) => (typeof v === 'number' ? formatNumber(v, 2) + ' dB'
      : v && v.angle_median_deg !== undefined ? formatNumber(v.angle_median_deg, 2) + '\u00b0 median' : '-');
    return (get('bytes.images') || []).map((i) => i.file + ' (' + i.width + ' \u00d7 ' + i.height + ', ' + i.codec +
      (i.quality !== undefined ? ' q' + i.quality : '') + ', ' + formatNumber(i.bytes / 1024, 0) + ' KiB: ' +
      Object.entries(i.written_psnr_db || {}).map(([slot, v]) => slot + ' ' + figure(v)).join(', ') + ')').join('; ');
  }

  /// --compare-reencode: the input's own images re-encoded at the output's PSNR, beside the output's bytes.
  function reencodeFigures() {
    const r = get('bytes.reencode');
    if (!r) return 'not measured (--compare-reencode)';
    if (r.quality === undefined) return r.reason || '-';
    return r.codec + ' q' + r.quality + ': ' + formatNumber(r.bytes_at_written_psnr / 1024, 0) + ' KiB at the output\'s PSNR; ' +
      'the output takes ' + formatNumber(r.output_over_reencode, 2) + '\u00d7 that' + (r.reason ? ' (' + r.reason + ')' : '');
  }

  function summaryRows(input, output) {
    const dash = () => document.createTextNode('');
    const must0 = (path) => (get(path) || 0) !== 0;
    return [
      ['Texels used (utilization)', reportNumber('metrics.input.utilization', 1, 100, ' %'),
        reportNumber('metrics.output.utilization', 1, 100, ' %'),
        "Share of the texture's texels that some triangle covers; the rest is memory that holds nothing."],
      ['Texels used', reportNumber('metrics.input.used_texels', 0), reportNumber('metrics.output.used_texels', 0),
        "The texels that carry the surface's colour: the texture budget the model really holds."],
      ['Texture size', textureSizes(input), textureSizes(output),
        'Every texture page, width \u00d7 height in texels.'],
      ['Texture bytes', reportNumber('bytes.input.total', 0, 1 / 1024, ' KiB'), reportNumber('bytes.output.total', 0, 1 / 1024, ' KiB'),
        'What the images the materials bind take on disk, every map included. The output is written as ' +
        (get('bytes.encoding.format') || '?') + ': ' + (get('bytes.encoding.reason') || '') + '.'],
      ['Surface PSNR as written', dash(), reportNumber('bytes.surface_psnr_written_db', 2, 1, ' dB'),
        'The surface PSNR of the images as written (a lossy codec decoded back), against the input.'],
      ['Written images', dash(), document.createTextNode(writtenImages()),
        'Every image the output binds: its size, codec and quality, bytes, and the written figure of each slot it serves (docs/metrics.md).'],
      ['Input re-encoded at that PSNR', document.createTextNode(reencodeFigures()), dash(),
        "The input's own images re-encoded in the output's codec without repacking (what gltf-transform or gltfpack would do), " +
        "at the lowest quality that reaches the output's surface PSNR: what tightex saves (docs/metrics.md)."],
      ['Surface PSNR', dash(), reportNumber('metrics.surface_psnr_db', 2, 1, ' dB'),
        "How closely the output's colours match the input's, at " + formatNumber(get('metrics.psnr_samples') || 0, 0) +
        ' points spread evenly over the surface. Higher is better; above about 40 dB differences are hard to see.'],
      ['Charts', formatNumber(input.charts, 0), reportNumber('metrics.charts', 0),
        'Separate pieces the texture is cut into. tightex aims at one per connected surface.'],
      ['Seam length', reportNumber('metrics.seam_length.input', 2), reportNumber('metrics.seam_length.output', 2),
        'Total length of the texture seams over the square root of the surface area. Seams are where texture filtering can show a line.'],
      ['Lost triangles', dash(), reportNumber('metrics.lost_triangles', 0),
        'Input triangles missing from the output. Must be 0.', must0('metrics.lost_triangles')],
      ['Flipped triangles', dash(), reportNumber('metrics.flipped', 0),
        'Triangles mirrored in texture space. Must be 0.', must0('metrics.flipped')],
      ['Degenerate triangles', dash(), reportNumber('metrics.degenerate', 0),
        'Triangles that own no texel (zero area in texture space). Must be 0.', must0('metrics.degenerate')],
      ['Overlap', dash(), reportNumber('metrics.overlap', 2, 100, ' %'),
        'Texels that two triangles share. Must be 0.', must0('metrics.overlap')],
      ['Density spread (P5 / P50 / P95)', dash(),
        joined(['p5', 'p50', 'p95'].map((q) => reportNumber('metrics.density_spread.' + q, 2)), ' / '),
        'log2 of texels per unit of surface area relative to the mean, at the 5 %, 50 % and 95 % points of the surface. ' +
        '0 everywhere is an even density; \u22121 is half the mean, +1 twice it.'],
      ['Detail loss area', dash(), reportNumber('metrics.detail_loss_area', 2, 100, ' %'),
        "Surface where the output has less than half the input's texels per area: blurred by more than a factor 2."],
      ['Angle distortion (mean / P95)', dash(),
        joined([reportNumber('metrics.angle_distortion.mean', 2), reportNumber('metrics.angle_distortion.p95', 2)], ' / '),
        "How much more each triangle is stretched one way than the other in texture space. 1 keeps shapes; a checkerboard's squares become rectangles as it grows."],
      ['Texture axes turned (mean / P95)', dash(),
        joined([reportNumber('metrics.texture_axes_angle_deg.mean', 1, 1, '\u00b0'), reportNumber('metrics.texture_axes_angle_deg.p95', 1, 1, '\u00b0')], ' / '),
        "How far the output turns the input texture's axes, modulo a right angle (0 to 45\u00b0). 0 keeps print straight, which lossy codecs store in fewer bytes; about 22\u00b0 is no better than random."],
      ['Components', dash(), reportNumber('preparation.components', 0),
        'Connected surfaces of the model. Each gets one chart (one rectangle of the texture).'],
      ['Holes filled / cut', dash(),
        joined([reportNumber('preparation.holes_filled', 0), reportNumber('preparation.holes_cut', 0)], ' / '),
        'Holes capped with scaffolding that shapes the map but owns no texel / holes opened into the chart border.'],
      ['Wall time', dash(), reportNumber('wall_seconds', 2, 1, ' s'), 'The whole command, from reading to writing (stages below).'],
      ['Peak memory', dash(), reportNumber('peak_rss_mib', 0, 1, ' MiB'), 'Most memory the command held at once.'],
    ];
  }

  function fillSummary(input, output) {
    const body = document.querySelector('#summary-table tbody');
    for (const [name, a, b, meaning, bad] of summaryRows(input, output)) {
      const row = el('tr', bad ? { class: 'bad' } : {}, [
        el('td', { text: name }), el('td', { class: 'n' }, [a]), el('td', { class: 'n' }, [b]),
        el('td', { class: 'meaning', text: meaning }),
      ]);
      body.append(row);
    }
    const file = (get('input.file') || '').split('/').pop();
    const out = get('output.model') || '';
    document.getElementById('subtitle').textContent =
      file + ' \u2192 ' + out + ' \u2014 map ' + get('options.map') + ', layout ' + get('options.layout') +
      ', holes ' + get('options.holes') + ', ' + formatNumber(get('input.triangles') || 0, 0) + ' triangles';
    document.title = 'tightex report: ' + file;
  }

  // ------------------------------------------------------------------------------------------------
  // Timings and components

  function fillTimings() {
    const body = document.querySelector('#timing-table tbody');
    (report.timings || []).forEach((t, i) => {
      const cell = (key, digits) =>
          el('td', {class: 'n'}, [typeof t[key] === 'number' ? reportNumber('timings.' + i + '.' + key, digits) : '']);
      body.append(
          el('tr', {},
             [el('td', {text: t.stage}), cell('seconds', 3), cell('user_seconds', 3), cell('sys_seconds', 3), cell('peak_rss_mib', 1)]));
    });
  }

  // The component table's columns: title, report key (numbers) or a function of the entry (text).
  const componentColumns = [
    ['#', 'index', 0], ['Triangles', 'triangles', 0], ['Area', 'area', 'sig3'], ['Genus', 'genus', 0],
    ['Boundary loops', 'boundary_loops', 0], ['Holes filled', 'holes_filled', 0], ['Holes cut', 'holes_cut', 0],
    ['Handle loops', (c) => (c.handle_loops || []).length, null], ['Cut', (c) => c.cut, null],
    ['Weights', (c) => c.weights, null],
    ['Density error before', (c) => pair(c.density_error_log2_before), null],
    ['Density error after', (c) => pair(c.density_error_log2), null],
    ['Rectangle (texels)', (c) => (c.rect ? c.rect.w + ' \u00d7 ' + c.rect.h : ''), null],
    ['Fallback', (c) => c.fallback || (c.kept_original_uvs ? 'kept input UVs: ' + c.kept_reason : 'no'), null],
  ];

  function pair(a) {
    return Array.isArray(a) && a.length === 2 ? formatNumber(a[0], 2) + ' / ' + formatNumber(a[1], 2) : '';
  }

  function componentCell(c, i, column) {
    const [, key, digits] = column;
    if (typeof key === 'string') return el('td', { class: 'n' }, [reportNumber('components.' + i + '.' + key, digits)]);
    const v = key(c);
    return el('td', typeof v === 'number' ? { class: 'n', text: String(v) } : { text: v });
  }

  function sortValue(c, column) {
    const key = column[1];
    const v = typeof key === 'string' ? c[key] : key(c);
    return v === undefined || v === null ? '' : v;
  }

  function fillComponents() {
    const comps = (report.components || []).map((c, i) => ({ c, i }));
    const table = document.getElementById('component-table');
    const head = el('tr');
    const body = table.tBodies[0];
    const render = () => {
      body.replaceChildren(...comps.map(({ c, i }) => el('tr', {}, componentColumns.map((col) => componentCell(c, i, col)))));
    };
    componentColumns.forEach((col, ci) => {
      const th = el('th', { tabindex: '0', scope: 'col', title: 'sort', text: col[0] });
      if (typeof col[1] === 'string') th.className = 'n';
      const sort = () => {
        const descending = th.getAttribute('aria-sort') === 'ascending';
        for (const other of head.children) other.removeAttribute('aria-sort');
        th.setAttribute('aria-sort', descending ? 'descending' : 'ascending');
        comps.sort((a, b) => {
          const x = sortValue(a.c, col), y = sortValue(b.c, col);
          const order = typeof x === 'number' && typeof y === 'number' ? x - y : String(x).localeCompare(String(y));
          return (descending ? -order : order) || a.i - b.i;
        });
        render();
      };
      th.addEventListener('click', sort);
      th.addEventListener('keydown', (e) => { if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); sort(); } });
      head.append(th);
    });
    table.tHead.append(head);
    render();
    const listed = comps.length, total = get('preparation.components') || listed;
    document.getElementById('components-note').textContent =
      (listed < total ? 'The ' + listed + ' largest of ' + total + ' components (and any that fell back). ' : '') +
      'Click a column title to sort. Map: ' + get('options.map') + ' for every component. ' +
      'Density error before / after: log2 of the texel density over the map\'s target at the 5 % and 95 % points of the component\'s area (0 is exact), for the first map and the final one.';
  }

  // ------------------------------------------------------------------------------------------------
  // The models as typed arrays

  function bytes(base64) {
    const binary = atob(base64);
    const out = new Uint8Array(binary.length);
    for (let i = 0; i < binary.length; ++i) out[i] = binary.charCodeAt(i);
    return out.buffer;
  }

  function decodeModel(m) {
    return {
      name: m.name, triangles: m.triangles, shown: m.shown, charts: m.charts, textures: m.textures,
      positions: new Float32Array(bytes(m.positions)), indices: new Uint32Array(bytes(m.indices)),
      uv: new Float32Array(bytes(m.uv)), texture: new Int16Array(bytes(m.texture)),
      seams: new Uint8Array(bytes(m.seams)), density: new Float32Array(bytes(m.density)),
    };
  }

  function loadImage(uri) {
    return new Promise((resolve, reject) => {
      if (!uri) { resolve(null); return; }
      const img = new Image();
      img.onload = () => resolve(img);
      img.onerror = () => reject(new Error('a texture image of the page does not decode'));
      img.src = uri;
    });
  }

  // ------------------------------------------------------------------------------------------------
  // Colours of the density heat map: blue (below the mean) through white to red (above), clamped to
  // +-kDensityRange (log2).

  const kDensityRange = 2;

  function densityColor(log2) {
    if (!Number.isFinite(log2) || log2 < -50) return [0.5, 0.5, 0.5];
    const t = Math.max(-1, Math.min(1, log2 / kDensityRange));
    const end = t < 0 ? [0.16, 0.36, 0.75] : [0.78, 0.16, 0.12];
    const a = Math.abs(t);
    return [1 + (end[0] - 1) * a, 1 + (end[1] - 1) * a, 1 + (end[2] - 1) * a];
  }

  function css(rgb) {
    return 'rgb(' + rgb.map((c) => Math.round(c * 255)).join(',') + ')';
  }

  // ------------------------------------------------------------------------------------------------
  // 2D: atlases, outlines, heat map

  // A canvas of `w` x `h` CSS pixels at the screen's resolution; the context draws in CSS pixels.
  function hiDpiCanvas(w, h) {
    const ratio = window.devicePixelRatio || 1;
    const canvas = el('canvas');
    canvas.width = Math.max(1, Math.round(w * ratio));
    canvas.height = Math.max(1, Math.round(h * ratio));
    canvas.style.width = w + 'px';
    canvas.style.height = h + 'px';
    const ctx = canvas.getContext('2d');
    ctx.scale(ratio, ratio);
    return { canvas, ctx };
  }

  // Calls f(t, x0, y0, x1, y1, x2, y2) for each shown triangle of `model` on texture `page`, in that
  // page's pixels at `scale` (a triangle beyond [0,1] drawn where the renderer's repeat puts it).
  function forTrianglesOn(model, page, w, h, f) {
    const uv = model.uv;
    for (let t = 0; t < model.shown; ++t) {
      if (model.texture[t] !== page) continue;
      const i = 6 * t;
      const du = Math.floor((uv[i] + uv[i + 2] + uv[i + 4]) / 3), dv = Math.floor((uv[i + 1] + uv[i + 3] + uv[i + 5]) / 3);
      f(t, (uv[i] - du) * w, (1 - uv[i + 1] + dv) * h, (uv[i + 2] - du) * w, (1 - uv[i + 3] + dv) * h,
        (uv[i + 4] - du) * w, (1 - uv[i + 5] + dv) * h);
    }
  }

  function drawOutlines(ctx, model, page, w, h) {
    ctx.beginPath();
    forTrianglesOn(model, page, w, h, (t, ...xy) => {
      const bits = model.seams[t];
      for (let k = 0; k < 3; ++k) {
        if (!(bits & (1 << k))) continue;
        const n = (k + 1) % 3;
        ctx.moveTo(xy[2 * k], xy[2 * k + 1]);
        ctx.lineTo(xy[2 * n], xy[2 * n + 1]);
      }
    });
    ctx.strokeStyle = 'rgba(255, 214, 0, 0.9)';
    ctx.lineWidth = 1;
    ctx.stroke();
  }

  // The figures of an output map's slots ("metallic_roughness + occlusion"), from metrics.maps: each
  // slot's surface PSNR against the input's map, or a normal map's angular error (median / P95).
  function mapFigures(slots) {
    const maps = get('metrics.maps') || [];
    const parts = [];
    for (const slot of slots.split(' + ')) {
      const i = maps.findIndex((f) => f.slot === slot);
      if (i < 0) continue;
      const key = 'metrics.maps.' + i + '.';
      parts.push('; ' + slot + ' ');
      if (typeof maps[i].surface_psnr_db === 'number') parts.push(reportNumber(key + 'surface_psnr_db', 1, 1, ' dB'));
      else parts.push(reportNumber(key + 'normal_angle_median_deg', 2), ' / ', reportNumber(key + 'normal_angle_p95_deg', 2, 1, '\u00b0'));
    }
    return parts;
  }

  function drawAtlases(models, images) {
    const row = document.getElementById('atlas-row');
    const pages = [];
    models.forEach((m, mi) => m.textures.forEach((t, ti) => pages.push({ m, mi, t, ti, img: images[mi][ti] })));
    const gap = 16, width = Math.max(320, row.clientWidth - gap * pages.length);
    const maxHeight = Math.max(...pages.map((p) => p.t.height), 1);
    const totalWidth = pages.reduce((s, p) => s + p.t.width, 0) || 1;
    const scale = Math.min(width / totalWidth, 440 / maxHeight);
    const draws = [];
    for (const p of pages) {
      const w = Math.max(1, Math.round(p.t.width * scale)), h = Math.max(1, Math.round(p.t.height * scale));
      const { canvas, ctx } = hiDpiCanvas(w, h);
      canvas.setAttribute('aria-label', p.m.name + ' texture ' + (p.ti + 1));
      const draw = (outlines) => {
        ctx.clearRect(0, 0, w, h);
        if (p.img) ctx.drawImage(p.img, 0, 0, w, h);
        if (outlines) drawOutlines(ctx, p.m, p.ti, w, h);
      };
      draws.push(draw);
      const used = p.mi === 0 ? 'metrics.input.image_utilization.' : 'metrics.output.image_utilization.';
      const caption = p.t.map
        ? el('figcaption', {}, [(p.mi === 0 ? 'Input ' : 'Output ') + p.t.map + ' map: ' + p.t.width + ' \u00d7 ' + p.t.height + ' texels',
          ...(p.mi === 0 ? [] : mapFigures(p.t.map))])
        : el('figcaption', {}, [(p.mi === 0 ? 'Input' : 'Output') + (p.m.textures.length > 1 ? ' page ' + (p.ti + 1) : '') +
          ': ' + p.t.width + ' \u00d7 ' + p.t.height + ' texels, ', reportNumber(used + p.ti, 1, 100, ' % used')]);
      // The page holds a downscaled copy; the full-size file beside it (or the input's) is linked.
      if (p.t.file) {
        caption.append(' (', el('a', { href: p.t.file.split('/').map(encodeURIComponent).join('/'), text: 'full size' }), ')');
      }
      row.append(el('figure', { class: 'atlas' }, [canvas, caption]));
    }
    const box = document.getElementById('show-outlines');
    const redraw = () => draws.forEach((d) => d(box.checked));
    box.addEventListener('change', redraw);
    redraw();
    document.getElementById('atlases').querySelector('.note').append(
      ' Scale: one screen pixel is ' + formatNumber(1 / scale, 1) + ' texels.');
  }

  // Fills the pixels whose centres lie in triangle (x0, y0) (x1, y1) (x2, y2) with `rgb` (bytes); a
  // triangle smaller than a pixel colours the pixel under its centroid, so that none disappears.
  function fillTriangle(image, rgb, x0, y0, x1, y1, x2, y2) {
    const W = image.width, H = image.height, px = image.data;
    const area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    const s = area < 0 ? -1 : 1;
    const minX = Math.max(0, Math.ceil(Math.min(x0, x1, x2) - 0.5)), maxX = Math.min(W - 1, Math.floor(Math.max(x0, x1, x2) - 0.5));
    const minY = Math.max(0, Math.ceil(Math.min(y0, y1, y2) - 0.5)), maxY = Math.min(H - 1, Math.floor(Math.max(y0, y1, y2) - 0.5));
    let filled = false;
    const put = (x, y) => {
      const i = 4 * (y * W + x);
      px[i] = rgb[0], px[i + 1] = rgb[1], px[i + 2] = rgb[2], px[i + 3] = 255;
    };
    for (let y = minY; y <= maxY && area !== 0; ++y) {
      const py = y + 0.5;
      for (let x = minX; x <= maxX; ++x) {
        const qx = x + 0.5;
        if (s * ((x1 - x0) * (py - y0) - (y1 - y0) * (qx - x0)) < 0) continue;
        if (s * ((x2 - x1) * (py - y1) - (y2 - y1) * (qx - x1)) < 0) continue;
        if (s * ((x0 - x2) * (py - y2) - (y0 - y2) * (qx - x2)) < 0) continue;
        put(x, y);
        filled = true;
      }
    }
    const cx = Math.floor((x0 + x1 + x2) / 3), cy = Math.floor((y0 + y1 + y2) / 3);
    if (!filled && cx >= 0 && cy >= 0 && cx < W && cy < H) put(cx, cy);
  }

  // The output atlas with each triangle coloured by its density, rasterised into the canvas's pixels
  // (far faster than a canvas path per triangle when there are hundreds of thousands).
  function drawHeatmaps(output) {
    const holder = document.getElementById('heatmaps');
    const colors = Array.from({ length: 257 }, (_, i) => densityColor(((i / 128) - 1) * kDensityRange).map((c) => Math.round(c * 255)));
    const grey = [128, 128, 128];
    output.textures.forEach((t, page) => {
      if (t.map) return;  // a map shares its base colour page's layout and density
      const scale = 420 / Math.max(t.width, t.height);
      const { canvas, ctx } = hiDpiCanvas(Math.round(t.width * scale), Math.round(t.height * scale));
      canvas.id = page === 0 ? 'heatmap' : 'heatmap-' + page;
      canvas.setAttribute('aria-label', 'output texel density heat map');
      const image = ctx.createImageData(canvas.width, canvas.height);
      for (let i = 0; i < image.data.length; i += 4) image.data.set([43, 45, 48, 255], i);
      forTrianglesOn(output, page, canvas.width, canvas.height, (tri, ...xy) => {
        const d = output.density[tri];
        const rgb = Number.isFinite(d) && d > -50 ? colors[Math.round((Math.max(-1, Math.min(1, d / kDensityRange)) + 1) * 128)] : grey;
        fillTriangle(image, rgb, ...xy);
      });
      ctx.putImageData(image, 0, 0);
      holder.append(el('figure', {}, [canvas, el('figcaption', { text: 'Output' + (output.textures.length > 1 ? ' page ' + (page + 1) : '') +
        ': texel density relative to the mean (log2)' })]));
    });
    drawColorbar();
  }

  function drawColorbar() {
    const w = 300, h = 18;
    const { canvas, ctx } = hiDpiCanvas(w, h);
    canvas.id = 'colorbar-scale';
    for (let x = 0; x < w; ++x) {
      ctx.fillStyle = css(densityColor(((x + 0.5) / w * 2 - 1) * kDensityRange));
      ctx.fillRect(x, 0, 1, h);
    }
    const ticks = el('div', { class: 'ticks', style: 'width:' + w + 'px' });
    const names = { '-2': '\u00bc\u00d7', '-1': '\u00bd\u00d7', '0': 'mean', '1': '2\u00d7', '2': '4\u00d7' };
    for (let v = -kDensityRange; v <= kDensityRange; ++v) {
      const label = (v > 0 ? '+' : v < 0 ? '\u2212' : '') + Math.abs(v) + '\n' + names[String(v)];
      ticks.append(el('span', { style: 'left:' + ((v / kDensityRange + 1) / 2 * 100) + '%', text: label }));
    }
    const box = document.getElementById('colorbar');
    box.append(el('div', { text: 'log2 texel density / mean' }), canvas, ticks,
      el('div', { class: 'muted', text: 'Clamped at \u00b1' + kDensityRange + '; grey: no texture.' }));
  }

  // ------------------------------------------------------------------------------------------------
  // 3D

  // A non-indexed geometry of the shown triangles grouped by texture (so each group takes its page's
  // material), with per-vertex density colours and seam segments.
  function buildGeometry(model) {
    const n = model.shown;
    const order = Array.from({ length: n }, (_, t) => t).sort((a, b) => model.texture[a] - model.texture[b] || a - b);
    const pos = new Float32Array(9 * n), uv = new Float32Array(6 * n), color = new Float32Array(9 * n);
    const seams = [];
    order.forEach((t, o) => {
      const rgb = densityColor(model.density[t]);
      for (let k = 0; k < 3; ++k) {
        const v = model.indices[3 * t + k];
        pos.set(model.positions.subarray(3 * v, 3 * v + 3), 9 * o + 3 * k);
        uv.set(model.uv.subarray(6 * t + 2 * k, 6 * t + 2 * k + 2), 6 * o + 2 * k);
        color.set(rgb, 9 * o + 3 * k);
      }
      for (let k = 0; k < 3; ++k) {
        if (!(model.seams[t] & (1 << k))) continue;
        const a = model.indices[3 * t + k], b = model.indices[3 * t + (k + 1) % 3];
        seams.push(...model.positions.subarray(3 * a, 3 * a + 3), ...model.positions.subarray(3 * b, 3 * b + 3));
      }
    });
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    geometry.setAttribute('uv', new THREE.Float32BufferAttribute(uv, 2));
    geometry.setAttribute('color', new THREE.Float32BufferAttribute(color, 3));
    const pageIds = [];
    for (let o = 0; o < n;) {
      let e = o;
      while (e < n && model.texture[order[e]] === model.texture[order[o]]) ++e;
      geometry.addGroup(3 * o, 3 * (e - o), pageIds.length);
      pageIds.push(model.texture[order[o]]);
      o = e;
    }
    const seamGeometry = new THREE.BufferGeometry();
    seamGeometry.setAttribute('position', new THREE.Float32BufferAttribute(new Float32Array(seams), 3));
    return { geometry, pageIds, seamGeometry };
  }

  function checkerTexture() {
    const size = 512, cells = 16;
    const canvas = document.createElement('canvas');
    canvas.width = canvas.height = size;
    const ctx = canvas.getContext('2d');
    for (let y = 0; y < cells; ++y)
      for (let x = 0; x < cells; ++x) {
        ctx.fillStyle = (x + y) % 2 ? '#3c3f44' : '#e9e9e6';
        ctx.fillRect(x * size / cells, y * size / cells, size / cells, size / cells);
      }
    const texture = new THREE.CanvasTexture(canvas);
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    texture.repeat.set(4, 4);
    texture.anisotropy = 4;
    return texture;
  }

  // A texture page for WebGL 1, which repeats and mipmaps only power-of-two images: three.js would
  // shrink any other to the power of two below (a 980-pixel page to 512, blurring the output next to
  // the input), so it is enlarged to the power of two above here instead.
  function pageTexture(img) {
    if (!img) return null;
    let source = img;
    const w = THREE.Math.ceilPowerOfTwo(img.width), h = THREE.Math.ceilPowerOfTwo(img.height);
    if (w !== img.width || h !== img.height) {
      source = document.createElement('canvas');
      source.width = w, source.height = h;
      const ctx = source.getContext('2d');
      ctx.imageSmoothingQuality = 'high';
      ctx.drawImage(img, 0, 0, w, h);
    }
    const texture = new THREE.Texture(source);
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    texture.anisotropy = 4;
    texture.needsUpdate = true;
    return texture;
  }

  // The materials of one model for each surface mode: per page for textures; one for the others.
  function materials(pageIds, pageTextures, checker) {
    const common = { side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 };
    const plain = new THREE.MeshBasicMaterial(Object.assign({ color: 0x9a9a9a }, common));
    return {
      texture: pageIds.map((p) => (p >= 0 && pageTextures[p] ? new THREE.MeshBasicMaterial(Object.assign({ map: pageTextures[p] }, common)) : plain)),
      density: new THREE.MeshBasicMaterial(Object.assign({ vertexColors: THREE.VertexColors }, common)),
      checker: new THREE.MeshBasicMaterial(Object.assign({ map: checker }, common)),
    };
  }

  function buildView(model, images, checker, seamColor, canvas) {
    const { geometry, pageIds, seamGeometry } = buildGeometry(model);
    const mats = materials(pageIds, images.map(pageTexture), checker);
    const mesh = new THREE.Mesh(geometry, mats.texture);
    const seams = new THREE.LineSegments(seamGeometry, new THREE.LineBasicMaterial({ color: seamColor }));
    seams.visible = false;
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0x2b2d30);
    scene.add(mesh, seams);
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    return { scene, renderer, mesh, seams, mats, canvas };
  }

  // The model's box: its centre and radius, and the axes of a three-quarter view: `up` upright,
  // looking mostly along `across`, a little from the `side`. Unless `upAxis` (0, 1, 2: x, y, z) says
  // which axis is up, a long or flat model stands on its longest extent and shows its broad face, and
  // a squat one (a bowl) on the extent that differs from the other two.
  function modelBox(positions, upAxis) {
    const box = new THREE.Box3().setFromArray(positions);
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    // The extents between the 2nd and 98th percentiles: a small floating fragment does not count.
    const size = [0, 1, 2].map((axis) => {
      const values = positions.filter((_, i) => i % 3 === axis).sort();
      return values[Math.floor(0.98 * (values.length - 1))] - values[Math.floor(0.02 * (values.length - 1))];
    });
    const [a, b, c] = [0, 1, 2].sort((i, j) => size[j] - size[i]);
    const squat = size[c] >= 0.5 * size[b] && size[a] - size[b] <= size[b] - size[c];
    let [up, across, side] = squat ? [c, b, a] : [a, c, b];
    if (upAxis !== undefined) {
      const others = [a, b, c].filter((i) => i !== upAxis);
      [up, across, side] = [upAxis, others[1], others[0]];
    }
    const unit = (i) => new THREE.Vector3().setComponent(i, 1);
    return { center: sphere.center, radius: sphere.radius || 1, up: unit(up), across: unit(across), side: unit(side) };
  }

  // The three-quarter view of modelBox, the whole model in the frame.
  function frame(camera, controls, box) {
    controls.target.copy(box.center);
    camera.near = box.radius / 100;
    camera.far = box.radius * 100;
    const direction = box.across.clone().multiplyScalar(0.9).add(box.up.clone().multiplyScalar(0.3))
      .add(box.side.clone().multiplyScalar(0.3)).normalize();
    // The bounding sphere holds the model with room to spare: frame a little inside it.
    const distance = box.radius / Math.tan((camera.fov / 2) * Math.PI / 180) * 0.9;
    camera.position.copy(box.center).add(direction.multiplyScalar(distance));
    camera.updateProjectionMatrix();
    controls.update();
  }

  function setupViewer(models, images) {
    const checker = checkerTexture();
    const views = [
      buildView(models[0], images[0], checker, 0xff9d00, document.getElementById('view-input')),
      buildView(models[1], images[1], checker, 0x00b8ff, document.getElementById('view-output')),
    ];
    const camera = new THREE.PerspectiveCamera(35, 4 / 3, 0.01, 100);
    const render = () => views.forEach((v) => v.renderer.render(v.scene, camera));
    // Two controls on one camera and one target: whichever view is dragged, both follow. They orbit
    // about the camera's up as it is when they are made, so a new up makes new controls.
    let controls = [];
    const upSelect = document.getElementById('up-axis');
    const reset = () => {
      const box = modelBox(models[0].positions, upSelect.value === 'auto' ? undefined : Number(upSelect.value));
      controls.forEach((c) => c.dispose());
      camera.up.copy(box.up);
      controls = views.map((v) => new THREE.OrbitControls(camera, v.canvas));
      controls[1].target = controls[0].target;
      controls.forEach((c) => c.addEventListener('change', render));
      frame(camera, controls[0], box);
      render();
    };
    const resize = () => {
      const w = views[0].canvas.parentElement.clientWidth, h = Math.round(Math.min(560, Math.max(240, w * 0.8)));
      views.forEach((v) => v.renderer.setSize(w, h, true));
      views.forEach((v) => { v.canvas.style.width = '100%'; });
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      render();
    };
    window.addEventListener('resize', resize);
    resize();
    reset();
    document.getElementById('reset-view').addEventListener('click', reset);
    upSelect.addEventListener('change', reset);
    const apply = () => {
      const mode = document.querySelector('input[name="surface"]:checked').value;
      const seams = document.getElementById('show-seams').checked;
      views.forEach((v) => { v.mesh.material = v.mats[mode]; v.seams.visible = seams; });
      render();
    };
    document.querySelectorAll('input[name="surface"], #show-seams').forEach((i) => i.addEventListener('change', apply));
    apply();
    return render;
  }

  function describeShown(models) {
    models.forEach((m, i) => {
      const id = i === 0 ? 'caption-input' : 'caption-output';
      const what = i === 0 ? 'Input' : 'Output';
      document.getElementById(id).textContent = what + ': ' + formatNumber(m.triangles, 0) + ' triangles, ' +
        formatNumber(m.charts, 0) + ' chart' + (m.charts === 1 ? '' : 's') + (m.shown < m.triangles ? ' (' + formatNumber(m.shown, 0) + ' shown)' : '');
    });
    const m = models[0];
    if (m.shown < m.triangles)
      document.getElementById('shown-note').textContent = 'To keep this page small, the views show both models decimated to ' +
        formatNumber(m.shown, 0) + ' and ' + formatNumber(models[1].shown, 0) + ' of their ' + formatNumber(m.triangles, 0) +
        ' triangles (at most ' + formatNumber(modelData.max_triangles, 0) +
        ': nearby vertices merged on one grid for both, each keeping its own texture coordinates and seams), and the atlas outlines and heat map those triangles; the atlases are downscaled copies, linked to their full-size files; the files hold every triangle.';
  }

  // ------------------------------------------------------------------------------------------------

  async function main() {
    const models = modelData.models.map(decodeModel);
    fillSummary(models[0], models[1]);
    fillTimings();
    fillComponents();
    describeShown(models);
    const images = await Promise.all(models.map((m) => Promise.all(m.textures.map((t) => loadImage(t.image)))));
    drawAtlases(models, images);
    drawHeatmaps(models[1]);
    if (typeof THREE === 'undefined' || !THREE.OrbitControls) throw new Error('three.js is missing from the page');
    const render = setupViewer(models, images);
    requestAnimationFrame(() => { render(); state.ready = true; document.documentElement.dataset.ready = 'true'; });
  }

  main().catch((e) => showError(e && e.message ? e.message : e));
})();
