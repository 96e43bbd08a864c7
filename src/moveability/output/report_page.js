// The interactive part of a moveability report: click poses on the regions
// drawing, read which regions hold them, whether they can be joined, and watch
// a motion through certified cells. Everything is computed here from the cells
// the report embeds (see moveability/output/report_cells.py); nothing is fetched.
(function () {
  "use strict";

  const YES = true;
  const NO = false;
  const UNKNOWN = null;
  const TWO_PI = 2.0 * Math.PI;

  function word(value) {
    return value === null ? "unknown" : value ? "yes" : "no";
  }

  function fail(root, message) {
    const box = root.querySelector(".explore-error");
    box.textContent = message;
    box.hidden = false;
    document.body.dataset.reportReady = "error";
  }

  async function inflate(text) {
    const binary = atob(text);
    const bytes = new Uint8Array(binary.length);
    for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  // ------------------------------------------------------------------ cells
  // The linear 2^k-tree of the page's cells, rebuilt from the cells' levels in
  // key order: the children of a cell are its split axes' bits, the first split
  // axis the most significant, as moveability.hypertree.keys orders them.
  class Cells {
    constructor(meta, bytes) {
      const k = meta.lo.length;
      const n = meta.n_cells;
      this.k = k;
      this.n = n;
      this.lo = meta.lo;
      this.hi = meta.hi;
      this.md = meta.max_depth;
      this.periodic = meta.periodic;
      this.classes = meta.classes;
      this.nLevels = Math.max(0, ...this.md);
      this.res = this.md.map((d) => 2 ** d);
      // (hi - lo) * 2^-depth is exact: each face is one rounding of the exact value
      this.unit = this.md.map((d, a) => (this.hi[a] - this.lo[a]) * 2 ** -d);
      this.split = [];
      for (let level = 0; level < this.nLevels; level++) {
        this.split.push(this.md.map((d, a) => (d > level ? a : -1)).filter((a) => a >= 0));
      }
      this.levels = bytes.subarray(0, n);
      const width = meta.index_bytes;
      const raw = bytes.subarray(n, n + n * width);
      this.cellClass = new Uint16Array(n);
      for (let i = 0; i < n; i++) {
        this.cellClass[i] = width === 1 ? raw[i] : raw[2 * i] | (raw[2 * i + 1] << 8);
      }
      const shares = new Uint16Array(meta.n_folds * 2 * k);
      const at = n + n * width;
      for (let i = 0; i < shares.length; i++) {
        shares[i] = bytes[at + 2 * i] | (bytes[at + 2 * i + 1] << 8);
      }
      this.anchors = new Float64Array(n * k);
      this.children = [];
      this.base = [];
      let pos = 0;
      const build = (level, anchor) => {
        if (pos >= n) throw new Error("the cells end early");
        if (this.levels[pos] === level) {
          for (let a = 0; a < k; a++) this.anchors[pos * k + a] = anchor[a];
          pos += 1;
          return -pos;
        }
        if (this.levels[pos] < level || level >= this.nLevels) {
          throw new Error("the cells' levels do not make a tree");
        }
        const axes = this.split[level];
        const m = axes.length;
        const node = this.base.length;
        const start = this.children.length;
        this.base.push(start);
        for (let c = 0; c < 1 << m; c++) this.children.push(0);
        for (let c = 0; c < 1 << m; c++) {
          const child = anchor.slice();
          for (let r = 0; r < m; r++) {
            if ((c >> (m - 1 - r)) & 1) child[axes[r]] += 2 ** (this.md[axes[r]] - 1 - level);
          }
          this.children[start + c] = build(level + 1, child);
        }
        return node;
      };
      this.root = build(0, new Array(k).fill(0));
      if (pos !== n) throw new Error("cells are left over");
      for (let a = 0; a < k; a++) {
        let sum = 0;
        for (let i = 0; i < n; i++) sum += this.anchors[i * k + a];
        if (sum !== meta.anchor_sums[a]) throw new Error("the rebuilt cells do not match");
      }
      // hub and fold point of each cell holding a fold group member, in cell order
      this.folds = new Map();
      for (let i = 0; i < n; i++) {
        if (!this.cls(i)[2].some((region) => region[2].length)) continue;
        const f = this.folds.size;
        if (f >= meta.n_folds) throw new Error("more fold cells than fold points");
        const [lo, hi] = this.box(i);
        const point = (which) =>
          lo.map((v, a) => v + (shares[(2 * f + which) * k + a] / 65535) * (hi[a] - v));
        this.folds.set(i, [point(0), point(1)]);
      }
      if (this.folds.size !== meta.n_folds) throw new Error("fold points are left over");
    }

    // hub and fold point of a fold cell, null for other cells
    fold(cell) {
      const found = this.folds.get(cell);
      return found === undefined ? null : found;
    }

    size(cell, axis) {
      return 2 ** (this.md[axis] - Math.min(this.levels[cell], this.md[axis]));
    }

    coordinate(axis, i) {
      return i >= this.res[axis] ? this.hi[axis] : i * this.unit[axis] + this.lo[axis];
    }

    box(cell) {
      const lo = [];
      const hi = [];
      for (let a = 0; a < this.k; a++) {
        const i = this.anchors[cell * this.k + a];
        lo.push(this.coordinate(a, i));
        hi.push(this.coordinate(a, i + this.size(cell, a)));
      }
      return [lo, hi];
    }

    centre(cell) {
      const [lo, hi] = this.box(cell);
      return lo.map((v, a) => 0.5 * (v + hi[a]));
    }

    // the finest-grid position of a coordinate, as moveability.hypertree.measurement
    // locates points: half-open cells, the top face of the box in the last cell
    gridAt(axis, v) {
      const res = this.res[axis];
      let g = Math.floor(((v - this.lo[axis]) / (this.hi[axis] - this.lo[axis])) * res);
      g = Math.min(Math.max(g, 0), res - 1);
      if (this.coordinate(axis, g) > v) g -= 1;
      if (this.coordinate(axis, g + 1) <= v && g + 1 < res) g += 1;
      return Math.min(Math.max(g, 0), res - 1);
    }

    inside(point) {
      for (let a = 0; a < this.k; a++) {
        if (!(point[a] >= this.lo[a] && point[a] <= this.hi[a])) return false;
      }
      return true;
    }

    // the cell holding a point, -1 outside the box
    locate(point) {
      if (!this.inside(point)) return -1;
      const g = point.map((v, a) => this.gridAt(a, v));
      let entry = this.root;
      let level = 0;
      while (entry >= 0) {
        let c = 0;
        for (const a of this.split[level]) {
          c = 2 * c + (Math.floor(g[a] / 2 ** (this.md[a] - 1 - level)) % 2);
        }
        entry = this.children[this.base[entry] + c];
        level += 1;
      }
      return -entry - 1;
    }

    // cells meeting the finest-grid box [qlo, qhi)
    query(qlo, qhi, out) {
      const k = this.k;
      const visit = (entry, level, anchor) => {
        for (let a = 0; a < k; a++) {
          const size = 2 ** (this.md[a] - Math.min(level, this.md[a]));
          if (anchor[a] >= qhi[a] || anchor[a] + size <= qlo[a]) return;
        }
        if (entry < 0) {
          out.push(-entry - 1);
          return;
        }
        const axes = this.split[level];
        const m = axes.length;
        const start = this.base[entry];
        for (let c = 0; c < 1 << m; c++) {
          const child = anchor.slice();
          for (let r = 0; r < m; r++) {
            if ((c >> (m - 1 - r)) & 1) child[axes[r]] += 2 ** (this.md[axes[r]] - 1 - level);
          }
          visit(this.children[start + c], level + 1, child);
        }
      };
      visit(this.root, 0, new Array(k).fill(0));
      return out;
    }

    // cells whose closed boxes meet the cell's, each with its shift in whole
    // turns along the periodic axes
    touching(cell) {
      const k = this.k;
      const pieces = [];
      for (let a = 0; a < k; a++) {
        const lo = this.anchors[cell * k + a];
        const size = this.size(cell, a);
        const res = this.res[a];
        const list = [[Math.max(lo - 1, 0), Math.min(lo + size + 1, res), 0]];
        if (this.periodic.includes(a) && size < res) {
          if (lo === 0) list.push([res - 1, res, -1]);
          if (lo + size === res) list.push([0, 1, 1]);
        }
        pieces.push(list);
      }
      const out = [];
      const combine = (a, qlo, qhi, shift) => {
        if (a === k) {
          const found = this.query(qlo, qhi, []);
          for (const other of found) {
            if (other !== cell || shift.some((s) => s !== 0)) out.push([other, shift.slice()]);
          }
          return;
        }
        for (const [lo, hi, s] of pieces[a]) {
          combine(a + 1, [...qlo, lo], [...qhi, hi], [...shift, s]);
        }
      };
      combine(0, [], [], []);
      return out;
    }

    cls(cell) {
      return this.classes[this.cellClass[cell]];
    }
  }

  // ---------------------------------------------------------------- answers
  class Answers {
    constructor(cells, meta) {
      this.cells = cells;
      this.regions = meta.regions;
      this.wrapLo = meta.wrap_lo;
    }

    // periodic coordinates into [lo, lo + 2 pi), as Analysis.as_poses wraps them
    wrap(pose) {
      const out = pose.slice();
      for (const a of this.cells.periodic) {
        const lo = this.wrapLo[a];
        const v = out[a];
        if (!(v >= lo && v < lo + TWO_PI)) {
          let m = (v - lo) % TWO_PI;
          if (m !== 0 && m < 0) m += TWO_PI;
          out[a] = lo + m;
        }
      }
      return out;
    }

    // per pose: its cell, W and each region as true / false / null
    point(pose) {
      const p = this.wrap(pose);
      const cell = this.cells.locate(p);
      if (cell < 0) {
        return { pose: p, cell, workspace: UNKNOWN, regions: this.regions.map(() => UNKNOWN) };
      }
      const [wc, wp, regions] = this.cells.cls(cell);
      return {
        pose: p,
        cell,
        workspace: wc ? YES : wp ? UNKNOWN : NO,
        regions: regions.map(([touch, postures]) =>
          postures.length ? YES : touch ? UNKNOWN : NO,
        ),
      };
    }

    locate(poses) {
      return {
        regions: this.regions.map((r) => r.id),
        points: poses.map((pose) => {
          const a = this.point(pose);
          const regions = {};
          this.regions.forEach((r, j) => (regions[String(r.id)] = a.regions[j]));
          return { pose: a.pose, workspace: a.workspace, regions };
        }),
      };
    }

    // Analysis.feasible from the cells: yes when one region certainly holds every
    // pose; unknown when a pose is outside the box or one possible component
    // meets every pose's cell; no otherwise
    feasible(poses) {
      const points = poses.map((pose) => this.point(pose));
      for (let j = 0; j < this.regions.length; j++) {
        if (points.every((a) => a.regions[j] === YES)) {
          return { feasible: YES, region: this.regions[j].id, index: j, points };
        }
      }
      const none = { feasible: UNKNOWN, region: null, index: -1, points };
      if (points.some((a) => a.cell < 0)) return none;
      const classes = points.map((a) => this.cells.cls(a.cell));
      for (let j = 0; j < this.regions.length; j++) {
        if (classes.every((c) => c[2][j][0])) return none;
      }
      const first = classes.length ? classes[0][3] : [];
      for (const e of first) {
        if (classes.every((c) => c[3].includes(e))) return none;
      }
      return { feasible: NO, region: null, index: -1, points };
    }
  }

  // ------------------------------------------------------------- mechanism
  // Each leg drawn as its polyline (fixed or sliding joint, ..., platform point)
  // from the closed-form inverse kinematics of its branch.
  function legPoints(leg, pose, branch) {
    const x = pose[0];
    const y = pose[1];
    if (leg.kind === "rr") {
      const [bx, by] = leg.base;
      const dx = x - bx;
      const dy = y - by;
      const rho = Math.hypot(dx, dy);
      const a = leg.proximal;
      const b = leg.distal;
      const g = Math.min(Math.max((rho * rho + a * a - b * b) / (2 * a * rho), -1), 1);
      const alpha = Math.acos(g);
      const theta = Math.atan2(dy, dx);
      const q = branch === 0 ? theta + alpha : theta - alpha;
      return { joint: q, points: [[bx, by], [bx + a * Math.cos(q), by + a * Math.sin(q)], [x, y]] };
    }
    if (leg.kind === "slider") {
      const h = Math.sqrt(Math.max(leg.length * leg.length - y * y, 0));
      const q = branch === 0 ? x + h : x - h;
      return { joint: q, points: [[q, 0], [x, y]] };
    }
    if (leg.kind === "rpr") {
      const c = Math.cos(pose[2]);
      const s = Math.sin(pose[2]);
      const [px, py] = leg.platform;
      const tx = x + (c * px - s * py);
      const ty = y + (s * px + c * py);
      const q = Math.hypot(tx - leg.base[0], ty - leg.base[1]);
      return { joint: q, points: [leg.base.slice(), [tx, ty]] };
    }
    return null;
  }

  function mechanismAt(meta, pose, posture) {
    const branches = meta.postures[posture];
    return meta.legs.map((leg, i) => legPoints(leg, pose, branches[i]));
  }

  function jointText(meta, legs) {
    return legs
      .map((leg, i) => {
        if (leg === null) return null;
        const limit = meta.limits[i];
        let q = leg.joint;
        if (!limit.prismatic) q = limit.lo + (((q - limit.lo) % TWO_PI) + TWO_PI) % TWO_PI;
        return `${meta.joint_names[i]} = ${q.toFixed(3)}${limit.prismatic ? "" : " rad"}`;
      })
      .filter((t) => t !== null)
      .join(", ");
  }

  // ----------------------------------------------------------------- motion
  // The certified part of region j as a graph over (cell, posture): a posture
  // certified regular over a cell, or a member of a certified fold group there.
  // Touching cells join in one posture when one of them is regular in it; in a
  // fold cell the members of its group that differ only on its folding legs
  // join (the posture changes at the fold point). These are edges of the
  // library's certain graph.
  class RegionGraph {
    constructor(cells, meta, j) {
      this.cells = cells;
      this.j = j;
      this.P = meta.postures.length;
      this.postures = meta.postures;
      this.near = new Map();
    }

    regular(cell) {
      return this.cells.cls(cell)[2][this.j][1];
    }

    group(cell) {
      return this.cells.cls(cell)[2][this.j][2];
    }

    touching(cell) {
      let found = this.near.get(cell);
      if (found === undefined) {
        found = this.cells.touching(cell);
        this.near.set(cell, found);
      }
      return found;
    }

    neighbours(node) {
      const cell = Math.floor(node / this.P);
      const p = node % this.P;
      const regular = this.regular(cell).includes(p);
      const out = [];
      for (const [other, shift] of this.touching(cell)) {
        const there = this.regular(other).includes(p);
        if ((regular || there) && (there || this.group(other).includes(p))) {
          out.push([other * this.P + p, shift]);
        }
      }
      const group = this.group(cell);
      if (group.includes(p)) {
        const folding = this.cells.cls(cell)[4];
        for (const q of group) {
          if (q === p) continue;
          const same = this.postures[p].every(
            (b, leg) => b === this.postures[q][leg] || folding.includes(leg),
          );
          if (same) out.push([cell * this.P + q, null]);
        }
      }
      return out;
    }

    // a shortest chain of nodes from one of the sources to one of the targets
    route(sources, targets) {
      const previous = new Map();
      const queue = [];
      for (const s of sources) {
        previous.set(s, null);
        queue.push(s);
      }
      for (let head = 0; head < queue.length; head++) {
        const node = queue[head];
        if (targets.has(node)) {
          // [node, its link to the next: a shift in turns, or null for a posture change]
          const chain = [node];
          const links = [];
          for (let at = previous.get(node); at !== null; at = previous.get(at[0])) {
            chain.push(at[0]);
            links.push(at[1]);
          }
          chain.reverse();
          links.reverse();
          return chain.map((n, i) => [n, i < links.length ? links[i] : null]);
        }
        for (const [next, shift] of this.neighbours(node)) {
          if (!previous.has(next)) {
            previous.set(next, [node, shift]);
            queue.push(next);
          }
        }
      }
      return null;
    }
  }

  // The corners of a motion through the poses, each with the posture of the
  // segment ending there: from a pose to its cell's centre, through the middle
  // of what consecutive cells share and the next centre; through a fold cell by
  // its hub, changing posture at its fold point. Periodic coordinates unwrap.
  function motionCorners(cells, answers, graph, poses) {
    const P = graph.P;
    const k = cells.k;
    const period = cells.hi.map((h, a) => h - cells.lo[a]);
    const points = poses.map((pose) => answers.point(pose));
    const nodes = (cell) => graph.regular(cell).map((p) => cell * P + p);
    let offset = new Array(k).fill(0);
    const corners = [];
    const add = (pose, posture) => corners.push([pose.map((v, a) => v + offset[a]), posture]);
    let sources = nodes(points[0].cell);
    for (let i = 0; i + 1 < points.length; i++) {
      const steps = graph.route(sources, new Set(nodes(points[i + 1].cell)));
      if (steps === null) return null;
      const first = steps[0][0] % P;
      if (i === 0) add(points[0].pose, first);
      add(cells.centre(points[i].cell), first);
      for (let s = 0; s + 1 < steps.length; s++) {
        const [u, link] = steps[s];
        const v = steps[s + 1][0];
        const cu = Math.floor(u / P);
        const cv = Math.floor(v / P);
        const pu = u % P;
        const pv = v % P;
        const fold = cells.fold(cu);
        if (cu === cv) {
          const [hub, point] = fold;
          add(hub, pu);
          add(point, pu);
          add(point, pv);
          add(hub, pv);
          continue;
        }
        if (fold !== null) add(fold[0], pu);
        const [ulo, uhi] = cells.box(cu);
        const [vlo, vhi] = cells.box(cv);
        const moved = link.map((t, a) => t * period[a]);
        add(
          ulo.map((x, a) => 0.5 * (Math.max(x, vlo[a] + moved[a]) + Math.min(uhi[a], vhi[a] + moved[a]))),
          pu,
        );
        offset = offset.map((o, a) => o + moved[a]);
        if (cells.fold(cv) === null) add(cells.centre(cv), pv);
      }
      const last = steps[steps.length - 1][0];
      add(points[i + 1].pose, last % P);
      sources = [last];
    }
    return corners;
  }

  // frames evenly spaced along the corners (distances in units of the box)
  function sample(corners, scale, frames) {
    const lengths = [];
    let total = 0;
    for (let i = 1; i < corners.length; i++) {
      const d = Math.hypot(...corners[i][0].map((v, a) => (v - corners[i - 1][0][a]) / scale[a]));
      lengths.push(d);
      total += d;
    }
    if (total === 0) return [corners[corners.length - 1]];
    const count = Math.max(2, Math.min(frames, Math.ceil(total / 0.004)));
    const out = [];
    let segment = 0;
    let start = 0;
    for (let f = 0; f < count; f++) {
      const s = (total * f) / (count - 1);
      while (segment < lengths.length - 1 && start + lengths[segment] < s) {
        start += lengths[segment];
        segment += 1;
      }
      const t = lengths[segment] > 0 ? Math.min(Math.max((s - start) / lengths[segment], 0), 1) : 1;
      const a = corners[segment][0];
      const b = corners[segment + 1][0];
      out.push([a.map((v, axis) => v + t * (b[axis] - v)), corners[segment + 1][1]]);
    }
    return out;
  }

  // ------------------------------------------------------------------- page
  function setup(root, meta, cells) {
    const answers = new Answers(cells, meta);
    const k = cells.k;
    const base = root.querySelector("canvas.explore-cells");
    const overlay = root.querySelector("canvas.explore-overlay");
    const frame = root.querySelector(".explore-frame");
    const view = meta.view; // [x0, y0, x1, y1]
    const scale = Math.min(
      meta.canvas_width / (view[2] - view[0]),
      meta.canvas_height / (view[3] - view[1]),
    );
    const width = Math.round((view[2] - view[0]) * scale);
    const height = Math.round((view[3] - view[1]) * scale);
    const ratio = window.devicePixelRatio || 1;
    for (const canvas of [base, overlay]) {
      canvas.style.width = `${width}px`;
      canvas.style.height = `${height}px`;
      canvas.width = Math.round(width * ratio);
      canvas.height = Math.round(height * ratio);
    }
    frame.style.width = `${width}px`;
    frame.style.height = `${height}px`;
    root.querySelector(".explore-main").style.width = `${width + 2}px`;
    overlay.dataset.view = view.join(",");
    overlay.dataset.scale = String(scale);
    const px = (x) => (x - view[0]) * scale;
    const py = (y) => (view[3] - y) * scale;
    const toPose = (u, v) => [view[0] + u / scale, view[3] - v / scale];

    const state = {
      poses: [],
      shown: meta.regions.map(() => true),
      slice: k === 3 ? 0.5 * (cells.lo[2] + cells.hi[2]) : null,
      motion: null,
      frameIndex: 0,
      playing: true,
    };

    // ---------------------------------------------------------- the cells
    function drawCells() {
      const ctx = base.getContext("2d");
      ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
      ctx.clearRect(0, 0, width, height);
      let g = null;
      if (k === 3) g = cells.gridAt(2, answers.wrap([0, 0, state.slice])[2]);
      const visible = [];
      for (let i = 0; i < cells.n; i++) {
        if (g !== null) {
          const a = cells.anchors[i * 3 + 2];
          if (!(a <= g && g < a + cells.size(i, 2))) continue;
        }
        if (cells.cls(i)[1]) visible.push(i);
      }
      // each set drawn opaque on a layer with cell edges on whole device pixels
      // (neighbours share their edges: no seams), the layer then laid on at its
      // opacity: W certain (pale), undecided (grey); then each region shown, where
      // it may extend (light) and where it certainly is (strong)
      const layer = document.createElement("canvas");
      layer.width = base.width;
      layer.height = base.height;
      const lctx = layer.getContext("2d");
      const snap = (v) => Math.round(v * ratio);
      const paint = (color, alpha, keep) => {
        lctx.clearRect(0, 0, layer.width, layer.height);
        lctx.fillStyle = color;
        for (const i of visible) {
          if (!keep(cells.cls(i))) continue;
          const [lo, hi] = cells.box(i);
          const x0 = snap(px(lo[0]));
          const y0 = snap(py(hi[1]));
          lctx.fillRect(x0, y0, snap(px(hi[0])) - x0, snap(py(lo[1])) - y0);
        }
        ctx.save();
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        ctx.globalAlpha = alpha;
        ctx.drawImage(layer, 0, 0);
        ctx.restore();
      };
      paint(meta.colors.workspace, 1, (c) => c[0]);
      paint(meta.colors.undecided, 1, (c) => !c[0]);
      meta.regions.forEach((region, j) => {
        if (!state.shown[j]) return;
        paint(region.color, 0.25, (c) => c[2][j][0] && !c[2][j][1].length);
        paint(region.color, 0.55, (c) => c[2][j][1].length > 0);
      });
      ctx.strokeStyle = "#555";
      ctx.lineWidth = 1;
      const x0 = px(cells.lo[0]);
      const y0 = py(cells.hi[1]);
      ctx.strokeRect(x0, y0, px(cells.hi[0]) - x0, py(cells.lo[1]) - y0);
      for (const leg of meta.legs) {
        if (leg.rail) {
          ctx.strokeStyle = "#999";
          ctx.lineWidth = 5;
          ctx.beginPath();
          ctx.moveTo(px(leg.rail[0][0]), py(leg.rail[0][1]));
          ctx.lineTo(px(leg.rail[1][0]), py(leg.rail[1][1]));
          ctx.stroke();
        }
      }
      base.dataset.drawn = String(visible.length);
    }

    // ------------------------------------------------------- the overlay
    function drawOverlay() {
      const ctx = overlay.getContext("2d");
      ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
      ctx.clearRect(0, 0, width, height);
      const motion = state.motion;
      if (motion && motion.corners) {
        ctx.strokeStyle = "#333";
        ctx.lineWidth = 1.2;
        ctx.setLineDash([4, 3]);
        ctx.beginPath();
        motion.corners.forEach(([v], i) =>
          i ? ctx.lineTo(px(v[0]), py(v[1])) : ctx.moveTo(px(v[0]), py(v[1])),
        );
        ctx.stroke();
        ctx.setLineDash([]);
        const [pose, posture] = motion.frames[state.frameIndex];
        const legs = mechanismAt(meta, pose, posture);
        const color = meta.posture_colors[posture % meta.posture_colors.length];
        if (meta.platform && legs.every((l) => l !== null)) {
          ctx.fillStyle = "rgba(0,0,0,0.08)";
          ctx.strokeStyle = "#222";
          ctx.lineWidth = 1.5;
          ctx.beginPath();
          legs.forEach((l, i) => {
            const [x, y] = l.points[l.points.length - 1];
            i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y));
          });
          ctx.closePath();
          ctx.fill();
          ctx.stroke();
        }
        for (const leg of legs) {
          if (leg === null) continue;
          ctx.strokeStyle = color;
          ctx.lineWidth = 3;
          ctx.beginPath();
          leg.points.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
          ctx.stroke();
          ctx.fillStyle = color;
          for (const [x, y] of leg.points) {
            ctx.beginPath();
            ctx.arc(px(x), py(y), 3, 0, TWO_PI);
            ctx.fill();
          }
          ctx.fillStyle = "#000";
          const [bx, by] = leg.points[0];
          ctx.fillRect(px(bx) - 4, py(by) - 4, 8, 8);
        }
        ctx.fillStyle = "#000";
        ctx.beginPath();
        ctx.arc(px(pose[0]), py(pose[1]), 3.5, 0, TWO_PI);
        ctx.fill();
        overlay.dataset.frame = String(state.frameIndex);
        overlay.dataset.mechanism = JSON.stringify(
          legs.map((l) => (l === null ? null : l.points.map((p) => p.map((v) => +v.toFixed(6))))),
        );
        const counter = root.querySelector(".motion-frame");
        counter.textContent =
          `frame ${state.frameIndex + 1} of ${motion.frames.length}: pose (` +
          pose.map((v) => v.toFixed(3)).join(", ") +
          `), posture ${meta.posture_names[posture]}` +
          (jointText(meta, legs) ? `, ${jointText(meta, legs)}` : "");
      }
      state.poses.forEach((pose, i) => {
        const x = px(pose[0]);
        const y = py(pose[1]);
        ctx.fillStyle = "#fff";
        ctx.strokeStyle = "#000";
        ctx.lineWidth = 2;
        ctx.beginPath();
        ctx.arc(x, y, 5, 0, TWO_PI);
        ctx.fill();
        ctx.stroke();
        ctx.fillStyle = "#000";
        ctx.font = "bold 12px sans-serif";
        ctx.fillText(`X${i + 1}`, x + 7, y - 7);
      });
    }

    // ------------------------------------------------------- the answers
    function update() {
      const tbody = root.querySelector(".pose-answers tbody");
      tbody.textContent = "";
      const located = state.poses.map((pose) => answers.point(pose));
      located.forEach((a, i) => {
        const row = document.createElement("tr");
        const cellsText = [`X${i + 1}`, `(${a.pose.map((v) => v.toFixed(3)).join(", ")})`];
        cellsText.push(word(a.workspace), ...a.regions.map(word));
        cellsText.forEach((text, c) => {
          const td = document.createElement("td");
          td.textContent = text;
          if (c > 1) td.className = `answer-${text}`;
          row.appendChild(td);
        });
        tbody.appendChild(row);
      });
      const out = root.querySelector(".feasible-answer");
      const status = root.querySelector(".motion-status");
      state.motion = null;
      state.frameIndex = 0;
      delete overlay.dataset.frame;
      delete overlay.dataset.mechanism;
      root.querySelector(".motion-frame").textContent = "";
      if (!state.poses.length) {
        out.dataset.answer = "none";
        out.textContent = "Click the drawing to add poses X1, X2, ...";
        status.dataset.state = "none";
        status.textContent = "";
        drawOverlay();
        return;
      }
      const result = answers.feasible(state.poses);
      const n = state.poses.length;
      const what = n === 1 ? "X1" : `X1 to X${n}`;
      if (result.feasible === YES) {
        out.dataset.answer = "yes";
        out.textContent =
          `Feasible: yes. Region ${result.region} certainly holds a configuration of every ` +
          `pose ${what}: a motion joins them without parallel singularity, within the joint limits.`;
      } else if (result.feasible === NO) {
        out.dataset.answer = "no";
        out.textContent =
          `Feasible: no. No region holds a configuration of every pose ${what}: ` +
          `the motion is not feasible.`;
      } else {
        out.dataset.answer = "unknown";
        out.textContent =
          `Feasible: unknown at this precision: a region may hold every pose ${what}, ` +
          `but its cells there are not certified.`;
      }
      out.className = `feasible-answer answer-${out.dataset.answer}`;
      status.dataset.state = "none";
      status.textContent = "";
      if (result.feasible === YES && n >= 2) {
        const graph = new RegionGraph(cells, meta, result.index);
        const corners = motionCorners(cells, answers, graph, state.poses);
        if (corners !== null) {
          const span = cells.hi.map((h, a) => h - cells.lo[a]);
          const frames = sample(corners, span, meta.max_frames);
          const used = [...new Set(frames.map((f) => meta.posture_names[f[1]]))];
          state.motion = { corners, frames };
          status.dataset.state = "playing";
          status.textContent =
            `Motion through certified cells of region ${result.region}, drawn at cell centres ` +
            "and along straight segments between them (through the hub of a cell where a leg " +
            `folds, changing posture at its fold point); postures ${used.join(", ")}. ` +
            "An illustration: the certified answer is the one above.";
        } else {
          status.dataset.state = "no-chain";
          status.textContent =
            "The page found no chain of cells it can draw joining the poses (the region " +
            "joins them through cells where the page knows no way across); " +
            "moveability plan computes such a motion.";
        }
      }
      drawOverlay();
    }

    function addPose(pose) {
      const full = pose.slice(0, 2);
      if (k === 3) full.push(pose.length > 2 ? pose[2] : state.slice);
      state.poses.push(full);
      update();
      return answers.point(full);
    }

    overlay.addEventListener("click", (event) => {
      const rect = overlay.getBoundingClientRect();
      addPose(toPose(event.clientX - rect.left, event.clientY - rect.top));
    });
    root.querySelector(".explore-undo").addEventListener("click", () => {
      state.poses.pop();
      update();
    });
    root.querySelector(".explore-clear").addEventListener("click", () => {
      state.poses = [];
      update();
    });
    const play = root.querySelector(".explore-play");
    play.addEventListener("click", () => {
      state.playing = !state.playing;
      play.textContent = state.playing ? "Pause" : "Play";
    });
    root.querySelectorAll(".explore-show input").forEach((box) => {
      box.addEventListener("change", () => {
        state.shown[Number(box.dataset.region)] = box.checked;
        drawCells();
      });
    });
    const planned = root.querySelector(".explore-planned");
    if (planned) {
      planned.addEventListener("click", () => {
        state.poses = [];
        for (const pose of meta.planned) state.poses.push(answers.wrap(pose));
        update();
      });
    }
    const slider = root.querySelector(".explore-slice");
    if (slider && k === 3) {
      const label = root.querySelector(".explore-slice-value");
      const show = () => {
        state.slice = Number(slider.value);
        const degrees = ((state.slice * 180) / Math.PI).toFixed(1);
        label.textContent = cells.periodic.includes(2)
          ? `${meta.pose_names[2]} = ${state.slice.toFixed(3)} rad (${degrees}°)`
          : `${meta.pose_names[2]} = ${state.slice.toFixed(3)}`;
        drawCells();
      };
      slider.addEventListener("input", show);
      show();
    }
    window.setInterval(() => {
      if (!state.motion || !state.playing) return;
      state.frameIndex = (state.frameIndex + 1) % state.motion.frames.length;
      drawOverlay();
    }, 40);

    drawCells();
    update();
    return {
      locate: (poses) => answers.locate(poses),
      feasible: (poses) => {
        const r = answers.feasible(poses);
        return { feasible: r.feasible, region: r.region };
      },
      toClient: (pose) => {
        const rect = overlay.getBoundingClientRect();
        return { x: rect.left + px(pose[0]), y: rect.top + py(pose[1]) };
      },
      fromClient: (x, y) => {
        const rect = overlay.getBoundingClientRect();
        return toPose(x - rect.left, y - rect.top);
      },
      addPose,
      clear: () => {
        state.poses = [];
        update();
      },
      setSlice: (value) => {
        if (slider) {
          slider.value = String(value);
          slider.dispatchEvent(new Event("input"));
        }
      },
      mechanism: (pose, posture) => mechanismAt(meta, pose, posture),
      poses: () => state.poses.map((p) => p.slice()),
      motion: () =>
        state.motion ? state.motion.frames.map(([pose, posture]) => [pose, posture]) : null,
      cells,
    };
  }

  async function start() {
    const root = document.getElementById("explore-tool");
    if (!root) return;
    const meta = JSON.parse(document.getElementById("explore-data").textContent);
    try {
      const bytes = await inflate(meta.cells_blob);
      const cells = new Cells(meta.cells, bytes);
      window.moveabilityReport = setup(root, meta, cells);
      document.body.dataset.reportReady = "yes";
    } catch (error) {
      fail(root, `The interactive drawing could not start: ${error.message}`);
    }
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", start);
  } else {
    start();
  }
})();
