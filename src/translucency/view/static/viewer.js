// translucency view: a fitted per-vertex model relit in WebGL2, no libraries, no server needed.
//
// Distant lights (directional, environment) by precomputed radiance transfer: every vertex holds its
// response t_{o,k} (radiance per unit weight of the real spherical harmonic Y_k, shadows and the
// subsurface transport included; translucency.transport.transfer), and the vertex shader sums
//     B_o = sum_k L_k t_{o,k}                                        (W/(mm^2 sr), per channel)
// with L_k the light's coefficients: the sky's projected coefficients turned about +z for the
// environment.  A directional light from w_l (L_k = E Y_k(w_l)) is sharp: its local part is taken
// exactly, with the vertex's own irradiance E_o = E cos+ V F (V from a shadow map), and only the rest
// r = t - a Ebar through the basis:  B_o = sum_k L_k r_{o,k} + a_o E_o  (the sky: + a_o sum_k L_k Ebar_{o,k}).  Point and spot lights (live viewer only) come as
// radiance per vertex from the server (POST /relight: irradiance with shadow rays + the sparse
// transport), as float16.  The exit: the incidence law's reciprocal factor F(mu_o; R1) / <F> per
// vertex and channel (a 2-D table), or Lambertian.  Then exposure and the sRGB curve.
"use strict";

(function () {
  const D = window.TL_DATA;
  const meta = D.meta;
  const $ = (id) => document.getElementById(id);

  // ---- arrays: base64 -> typed arrays ---------------------------------------------------------
  function decode(name) {
    const a = D.arrays[name];
    if (!a) return null;
    const bin = atob(a.b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const T = { int8: Int8Array, float32: Float32Array, float16: Uint16Array, uint32: Uint32Array, uint8: Uint8Array, uint16: Uint16Array }[a.dtype];
    return new T(bytes.buffer);
  }
  const toHalf = (() => { // number -> float16 bits (the exit table when none is stored)
    const f32 = new Float32Array(1), u32 = new Uint32Array(f32.buffer);
    return (v) => {
      f32[0] = v; const x = u32[0];
      const s = (x >> 16) & 0x8000, e = ((x >> 23) & 0xff) - 127 + 15, m = (x >> 13) & 0x3ff;
      if (e <= 0) return s; if (e >= 31) return s | 0x7c00; return s | (e << 10) | m;
    };
  })();

  const position = decode("position");       // (V, 3) float32, mm
  const normal = decode("normal");           // (V, 3) float16
  const index = decode("index");             // (F, 3) uint32
  const V = meta.vertices, F = meta.faces;

  // ---- real spherical harmonics (translucency.transport.sh: the same recurrence) -------------------
  function shBasis(w, bands) {
    const [x, y] = w, z = Math.max(-1, Math.min(1, w[2]));
    const phi = Math.atan2(y, x), s = Math.sqrt(Math.max(1 - z * z, 0));
    const P = {};
    let pmm = 1;
    for (let m = 0; m < bands; m++) {
      if (m > 0) pmm *= (2 * m - 1) * s;
      P[m + "," + m] = pmm;
      if (m + 1 < bands) P[(m + 1) + "," + m] = (2 * m + 1) * z * pmm;
      for (let l = m + 2; l < bands; l++)
        P[l + "," + m] = ((2 * l - 1) * z * P[(l - 1) + "," + m] - (l + m - 1) * P[(l - 2) + "," + m]) / (l - m);
    }
    const fact = (n) => { let r = 1; for (let i = 2; i <= n; i++) r *= i; return r; };
    const out = new Float64Array(bands * bands);
    for (let l = 0; l < bands; l++)
      for (let m = 0; m <= l; m++) {
        const K = Math.sqrt((2 * l + 1) / (4 * Math.PI) * fact(l - m) / fact(l + m));
        if (m === 0) out[l * (l + 1)] = K * P[l + ",0"];
        else {
          out[l * (l + 1) + m] = Math.SQRT2 * K * Math.cos(m * phi) * P[l + "," + m];
          out[l * (l + 1) - m] = Math.SQRT2 * K * Math.sin(m * phi) * P[l + "," + m];
        }
      }
    return out;
  }
  function shRotateZ(c, bands, gamma) { // c: Float64Array(K*3); L'(phi) = L(phi - gamma)
    const out = c.slice();
    for (let l = 1; l < bands; l++)
      for (let m = 1; m <= l; m++) {
        const cg = Math.cos(m * gamma), sg = Math.sin(m * gamma);
        for (let ch = 0; ch < 3; ch++) {
          const a = c[(l * (l + 1) + m) * 3 + ch], b = c[(l * (l + 1) - m) * 3 + ch];
          out[(l * (l + 1) + m) * 3 + ch] = a * cg - b * sg;
          out[(l * (l + 1) - m) * 3 + ch] = a * sg + b * cg;
        }
      }
    return out;
  }

  // ---- WebGL2 -------------------------------------------------------------------------------
  const canvas = $("canvas");
  const gl = canvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: false });
  if (!gl) { $("status").textContent = "This browser has no WebGL2."; return; }
  let bands = 0, K = 0;  // the light basis: set by installLight (at once on a page, later when served live)

  const VS = `#version 300 es
  precision highp float; precision highp int; precision highp sampler2D; precision highp sampler2DShadow;
  layout(location = 0) in vec3 a_pos;
  in vec3 a_normal; in vec3 a_r1; in vec3 a_invf; in vec3 a_direct; in float a_map; in uint a_vid;
  in vec3 a_trun; in float a_erun; in vec3 a_local; in vec3 b_trun; in float b_erun; in vec3 b_local;
  uniform mat4 u_mvp; uniform vec3 u_eye; uniform int u_mode; uniform int u_stride; uniform int u_texw;
  uniform sampler2D u_transfer; uniform float u_tscale; uniform float u_escale; uniform vec4 u_L[27]; uniform int u_kq;
  uniform sampler2D u_exit; uniform sampler2D u_in; uniform int u_exit_law; uniform vec3 u_tint;
  uniform int u_local; uniform vec3 u_Edir; uniform sampler2DShadow u_shadow; uniform mat4 u_lightmvp; uniform float u_offset; uniform float u_blur;
  uniform int u_spec; uniform vec3 u_lightdir; uniform vec3 u_lightpos; uniform int u_lightkind; uniform float u_f0;
  uniform float u_spec_e;
  uniform sampler2D u_transfer_b; uniform float u_tscale_b; uniform float u_escale_b; uniform int u_model; uniform vec3 u_shift;
  out vec3 v_radiance; out float v_map;
  float law(sampler2D table, float mu, float r1) { return texture(table, vec2(mu, r1)).r; }
  // the precomputed transfer of one model: B_c = sum_k L_{k,c} r_{k,c} + the local part (module comment)
  vec3 prt(sampler2D tex, vec3 trun, float erun, vec3 loc, float tscale, float escale, vec3 n) {
    int base = int(a_vid) * u_stride;
    vec3 B = vec3(0.0), Ebar = vec3(0.0);
    for (int j = 0; j < 9; j++) {
      if (j >= u_kq) break;
      vec4 t0 = texelFetch(tex, ivec2((base + j) % u_texw, (base + j) / u_texw), 0);
      vec4 t1 = texelFetch(tex, ivec2((base + u_kq + j) % u_texw, (base + u_kq + j) / u_texw), 0);
      vec4 t2 = texelFetch(tex, ivec2((base + 2 * u_kq + j) % u_texw, (base + 2 * u_kq + j) / u_texw), 0);
      B += vec3(dot(t0, u_L[j]), dot(t1, u_L[9 + j]), dot(t2, u_L[18 + j]));
      if (u_local == 0) {
        vec4 e = texelFetch(tex, ivec2((base + 3 * u_kq + j) % u_texw, (base + 3 * u_kq + j) / u_texw), 0);
        Ebar += vec3(dot(e, u_L[j]), dot(e, u_L[9 + j]), dot(e, u_L[18 + j]));
      }
    }
    B *= trun * tscale;                 // the rest r = t - a Ebar through the basis
    if (u_local == 0) B += loc * Ebar * erun * escale;   // the sky: a Ebar through it too
    else {                              // a directional light: its local part exactly
      float cl = dot(n, u_lightdir);
      if (cl > 0.0) {
        // the shadow, softened over the light's spread inside the body (8 taps on a disk of u_blur),
        // offset along the normal, more at grazing light (no self-shadow of the mesh's small bumps there)
        vec4 pl = u_lightmvp * vec4(a_pos + n * u_offset * (1.0 + 4.0 * (1.0 - cl)), 1.0);
        vec3 sc = pl.xyz * 0.5 + 0.5;
        float vis = 0.0;
        for (int t = 0; t < 8; t++) {
          float ang = 0.785398 * float(t) + 0.3, rad = u_blur * (t % 2 == 0 ? 1.0 : 0.5);
          vis += texture(u_shadow, vec3(sc.xy + rad * vec2(cos(ang), sin(ang)), sc.z));
        }
        vis *= 0.125;
        B += loc * u_Edir * cl * vis * vec3(law(u_in, cl, a_r1.r), law(u_in, cl, a_r1.g), law(u_in, cl, a_r1.b));
      }
    }
    return max(B, 0.0);
  }
  void main() {
    gl_Position = u_mvp * vec4(a_pos + u_shift, 1.0);
    vec3 n = normalize(a_normal);
    vec3 wo = normalize(u_eye - a_pos);
    float mu = clamp(dot(n, wo), 1e-3, 1.0);
    vec3 B = vec3(0.0);
    if (u_mode == 0 && u_model == 2) {  // the difference of two models: |B - A| / A, as a map
      vec3 A = prt(u_transfer, a_trun, a_erun, a_local, u_tscale, u_escale, n);
      vec3 Bb = prt(u_transfer_b, b_trun, b_erun, b_local, u_tscale_b, u_escale_b, n);
      v_map = dot(abs(Bb - A), vec3(1.0)) / max(dot(A, vec3(1.0)), 1e-12);
      v_radiance = vec3(0.0); return;
    }
    if (u_mode == 0) B = u_model == 1 ? prt(u_transfer_b, b_trun, b_erun, b_local, u_tscale_b, u_escale_b, n)
                                      : prt(u_transfer, a_trun, a_erun, a_local, u_tscale, u_escale, n);
    else if (u_mode == 1) {           // radiance from the server (point, spot)
      B = max(a_direct, 0.0) * u_tint;
    }
    if (u_exit_law == 1) {              // F(mu_o; R1) / <F>, per channel (or the boundary's exit)
      B *= vec3(law(u_exit, mu, a_r1.r), law(u_exit, mu, a_r1.g), law(u_exit, mu, a_r1.b)) * a_invf;
    }
    if (u_spec == 1 && u_mode <= 1) {   // the boundary's mirror-like reflection of a small light (GGX, a = 0.08)
      vec3 wl = u_lightkind == 0 ? u_lightdir : normalize(u_lightpos - a_pos);
      float cl = dot(n, wl);
      if (cl > 0.0) {
        vec3 h = normalize(wl + wo); float nh = max(dot(n, h), 0.0), a2 = 0.0064;
        float dd = nh * nh * (a2 - 1.0) + 1.0; float Dg = a2 / (3.14159265 * dd * dd);
        float Fr = u_f0 + (1.0 - u_f0) * pow(1.0 - max(dot(h, wo), 0.0), 5.0);
        B += u_spec_e * u_tint * Fr * Dg * cl / (4.0 * cl * mu);
      }
    }
    v_radiance = B; v_map = a_map;
  }`;
  const FS = `#version 300 es
  precision highp float; precision highp int;
  in vec3 v_radiance; in float v_map;
  uniform int u_mode; uniform float u_exposure; uniform vec2 u_range; uniform int u_flags; uniform int u_model;
  out vec4 colour;
  vec3 srgb(vec3 c) { c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c)); }
  vec3 viridis(float t) {
    const vec3 c0 = vec3(0.2777273272234177, 0.005407344544966578, 0.3340998053353061);
    const vec3 c1 = vec3(0.1050930431085774, 1.404613529898575, 1.384590162594685);
    const vec3 c2 = vec3(-0.3308618287255563, 0.214847559468213, 0.09509516302823659);
    const vec3 c3 = vec3(-4.634230498983486, -5.799100973351585, -19.33244095627987);
    const vec3 c4 = vec3(6.228269936347081, 14.17993336680509, 56.69055260068105);
    const vec3 c5 = vec3(4.776384997670288, -13.74514537774601, -65.35303263337234);
    const vec3 c6 = vec3(-5.435455855934631, 4.645852612178535, 26.3124352495832);
    return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
  }
  void main() {
    if (u_mode == 2 || (u_mode == 0 && u_model == 2)) {
      if (u_flags == 1) { colour = vec4(v_map > 0.5 ? vec3(0.9, 0.2, 0.15) : vec3(0.55), 1.0); return; }
      float t = clamp((v_map - u_range.x) / max(u_range.y - u_range.x, 1e-12), 0.0, 1.0);
      colour = vec4(viridis(t), 1.0); return;
    }
    colour = vec4(srgb(v_radiance * u_exposure), 1.0);
  }`;
  function shader(type, src) {
    const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  const prog = gl.createProgram();
  gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS)); gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
  gl.linkProgram(prog);
  if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
  gl.useProgram(prog);
  const U = {};
  for (const name of ["u_transfer_b", "u_tscale_b", "u_escale_b", "u_model", "u_shift", "u_blur", "u_escale", "u_in", "u_local", "u_Edir", "u_shadow", "u_lightmvp", "u_offset", "u_kq", "u_mvp", "u_eye", "u_mode", "u_stride", "u_texw", "u_transfer", "u_tscale", "u_L", "u_exit",
    "u_exit_law", "u_tint", "u_exposure", "u_range", "u_flags", "u_spec", "u_lightdir", "u_lightpos",
    "u_lightkind", "u_f0", "u_spec_e"]) U[name] = gl.getUniformLocation(prog, name);

  // two meshes: the full one, and (large objects) a reduced one drawn while the light or camera moves;
  // a reduced vertex takes the attributes and the transfer of the full vertex nearest it (a_vid)
  const perVertex = { a_normal: [normal, 3], a_r1: [null, 3], a_invf: [null, 3], a_trun: [null, 3], a_erun: [null, 1], a_local: [null, 3],
    b_trun: [null, 3], b_erun: [null, 1], b_local: [null, 3] };
  function gather(data, size, source) {
    if (!source) return data;
    const out = new data.constructor(source.length * size);
    for (let i = 0; i < source.length; i++) for (let q = 0; q < size; q++) out[i * size + q] = data[source[i] * size + q];
    return out;
  }
  function makeMesh(pos, idx, source) {
    const m = { vao: gl.createVertexArray(), count: idx.length, source, n: pos.length / 3, buf: {} };
    gl.bindVertexArray(m.vao);
    const put = (name, data, size, type) => {
      const loc = gl.getAttribLocation(prog, name); if (loc < 0) return;
      const b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(loc);
      if (type === gl.UNSIGNED_INT) gl.vertexAttribIPointer(loc, size, type, 0, 0); else gl.vertexAttribPointer(loc, size, type, false, 0, 0);
      m.buf[name] = b;
    };
    put("a_pos", pos, 3, gl.FLOAT);
    put("a_vid", source || Uint32Array.from({ length: m.n }, (_, i) => i), 1, gl.UNSIGNED_INT);
    for (const [name, [data, size]] of Object.entries(perVertex))
      put(name, data ? gather(data, size, source) : new Uint16Array(m.n * size).fill(0x3c00), size, gl.HALF_FLOAT);
    put("a_direct", new Uint16Array(m.n * 3), 3, gl.HALF_FLOAT);
    put("a_map", new Uint16Array(m.n), 1, gl.HALF_FLOAT);
    const ib = gl.createBuffer(); gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ib); gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
    return m;
  }
  const meshes = [makeMesh(position, index, null)];
  if (D.arrays.lod_position) meshes.push(makeMesh(decode("lod_position"), decode("lod_index"), decode("lod_source")));
  function upload(name, data, size) { // a per-vertex array of the full mesh, into every mesh
    for (const m of meshes) { gl.bindBuffer(gl.ARRAY_BUFFER, m.buf[name]); gl.bufferSubData(gl.ARRAY_BUFFER, 0, gather(data, size, m.source)); }
  }

  function texture(unit, w, h, data, filter) {
    const t = gl.createTexture(); gl.activeTexture(gl.TEXTURE0 + unit); gl.bindTexture(gl.TEXTURE_2D, t);
    if (filter === "snorm") gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8_SNORM, w, h, 0, gl.RGBA, gl.BYTE, data);
    else gl.texImage2D(gl.TEXTURE_2D, 0, gl.R16F, w, h, 0, gl.RED, gl.HALF_FLOAT, data);
    const f = filter === "linear" ? gl.LINEAR : gl.NEAREST;
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, f); gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, f);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE); gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return t;
  }
  let ready = false;
  function installLight(lm, arrays) { // the transfer, the exit law, the sky and the exposure
    Object.assign(meta, lm);
    const get = (name) => { const a = D.arrays[name]; D.arrays[name] = arrays[name]; const out = decode(name); D.arrays[name] = a; return out; };
    bands = meta.bands; K = bands * bands;
    const transfer = get("transfer");       // (rows * texture_width * 4) int8: 8-bit runs
    gl.useProgram(prog);
    texture(0, meta.texture_width, transfer.length / 4 / meta.texture_width, transfer, "snorm");
    const n = meta.exit_table_size, one = new Uint16Array(n * n).fill(toHalf(1));
    texture(1, n, n, get("exit_table") || one, "linear");
    texture(2, n, n, get("incidence_table") || one, "linear");
    for (const [attr, name, size] of [["a_r1", "r1", 3], ["a_invf", "inv_mean_f", 3], ["a_trun", "transfer_run", 3],
      ["a_erun", "irradiance_run", 1], ["a_local", "local", 3]]) if (arrays[name]) upload(attr, get(name), size);
    gl.uniform1i(U.u_transfer, 0); gl.uniform1i(U.u_exit, 1); gl.uniform1i(U.u_in, 2); gl.uniform1i(U.u_shadow, 3);
    gl.uniform1i(U.u_transfer_b, 4);
    if (arrays.b_transfer) { // a second model of the same mesh: beside this one, and their difference
      const tb = get("b_transfer");
      texture(4, meta.texture_width, tb.length / 4 / meta.texture_width, tb, "snorm");
      gl.useProgram(prog);
      for (const [attr, name, size] of [["b_trun", "b_transfer_run", 3], ["b_erun", "b_irradiance_run", 1], ["b_local", "b_local", 3]])
        upload(attr, get(name), size);
      gl.uniform1f(U.u_tscale_b, meta.compare.transfer_scale); gl.uniform1f(U.u_escale_b, meta.compare.irradiance_scale);
      for (const [k, label] of [["compare_b", "model B: " + meta.compare.name], ["compare_diff", "difference |B - A| / A"],
        ["compare_side", "A | B side by side"]]) $("show").add(new Option(label, k));
    } else texture(4, 1, 1, new Int8Array(4), "snorm");
    gl.uniform1f(U.u_escale, meta.irradiance_scale);
    gl.uniform1i(U.u_stride, meta.stride); gl.uniform1i(U.u_kq, meta.kq); gl.uniform1i(U.u_texw, meta.texture_width);
    gl.uniform1f(U.u_tscale, meta.transfer_scale);
    gl.uniform1i(U.u_exit_law, meta.exit_law ? 1 : 0);
    gl.uniform1f(U.u_f0, meta.eta === 1 ? 0 : Math.pow((meta.eta - 1) / (meta.eta + 1), 2));
    $("about").innerHTML = meta.about; $("subtitle").textContent = meta.subtitle;
    if (meta.eta !== 1) $("specular-row").classList.remove("hidden");
    ready = true; $("status").textContent = meta.status || "";
    if (!kinds.includes("environment") && meta.env) kinds.splice(1, 0, "environment");
    if (meta.live && state.show === meta.maps[0].key) { state.show = "radiance"; showChanged(); }
    syncControls();
    lightChanged();
  }
  gl.enable(gl.DEPTH_TEST); gl.enable(gl.CULL_FACE);

  // ---- the shadow map of a directional light: depth from the light, orthographic ----------------
  const SHADOW = 512;  // texels a side: the light's spread (u_blur) softens the map's steps
  const shadowProg = gl.createProgram();
  gl.attachShader(shadowProg, shader(gl.VERTEX_SHADER, `#version 300 es
    layout(location = 0) in vec3 a_pos; uniform mat4 u_lightmvp; void main() { gl_Position = u_lightmvp * vec4(a_pos, 1.0); }`));
  gl.attachShader(shadowProg, shader(gl.FRAGMENT_SHADER, `#version 300 es
    precision mediump float; void main() {}`));
  gl.linkProgram(shadowProg);
  const shadowTex = gl.createTexture(); gl.activeTexture(gl.TEXTURE3); gl.bindTexture(gl.TEXTURE_2D, shadowTex);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.DEPTH_COMPONENT24, SHADOW, SHADOW, 0, gl.DEPTH_COMPONENT, gl.UNSIGNED_INT, null);
  for (const [k, v] of [[gl.TEXTURE_MIN_FILTER, gl.LINEAR], [gl.TEXTURE_MAG_FILTER, gl.LINEAR], [gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE],
    [gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE], [gl.TEXTURE_COMPARE_MODE, gl.COMPARE_REF_TO_TEXTURE], [gl.TEXTURE_COMPARE_FUNC, gl.LEQUAL]])
    gl.texParameteri(gl.TEXTURE_2D, k, v);
  const shadowFb = gl.createFramebuffer(); gl.bindFramebuffer(gl.FRAMEBUFFER, shadowFb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.TEXTURE_2D, shadowTex, 0);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  let shadowKey = null;
  function lightMvp(w) { // orthographic, from the light's side, the whole object inside
    const h = size / 2, E = [C[0] + w[0] * size, C[1] + w[1] * size, C[2] + w[2] * size];
    const f = norm(sub(C, E)), s_ = norm(cross(f, Math.abs(w[2]) > 0.99 ? [1, 0, 0] : [0, 0, 1])), u = cross(s_, f);
    const view = [s_[0], u[0], -f[0], 0, s_[1], u[1], -f[1], 0, s_[2], u[2], -f[2], 0, -dot(s_, E), -dot(u, E), dot(f, E), 1];
    const nr = 0.1 * size, fr = 2 * size;
    const proj = [1 / h, 0, 0, 0, 0, 1 / h, 0, 0, 0, 0, -2 / (fr - nr), 0, 0, 0, -(fr + nr) / (fr - nr), 1];
    return mul(proj, view);
  }
  function renderShadow(mesh, m) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, shadowFb); gl.viewport(0, 0, SHADOW, SHADOW); gl.clear(gl.DEPTH_BUFFER_BIT);
    gl.useProgram(shadowProg); gl.uniformMatrix4fv(gl.getUniformLocation(shadowProg, "u_lightmvp"), false, m);
    gl.bindVertexArray(mesh.vao); gl.cullFace(gl.FRONT);  // the far sides: no acne on the lit ones
    gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_INT, 0);
    gl.cullFace(gl.BACK); gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  // ---- camera: orbit about the object's centre, +z up ---------------------------------------
  const C = meta.centre, size = meta.size;
  const cam = { az: meta.view.az, el: meta.view.el, dist: 1.9 * size };
  function eye() { // (further back while two models stand side by side)
    const a = cam.az * Math.PI / 180, e = cam.el * Math.PI / 180;
    const dist = cam.dist * (state.show === "compare_side" ? 1.8 : 1);
    return [C[0] + dist * Math.cos(e) * Math.cos(a), C[1] + dist * Math.cos(e) * Math.sin(a), C[2] + dist * Math.sin(e)];
  }
  function mvp() {
    const E = eye(), f = norm(sub(C, E)), s = norm(cross(f, [0, 0, 1])), u = cross(s, f);
    const view = [s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
      -dot(s, E), -dot(u, E), dot(f, E), 1];
    const asp = canvas.width / canvas.height, fov = 30 * Math.PI / 180, t = 1 / Math.tan(fov / 2);
    const near = cam.dist * 0.05, far = cam.dist * 8;
    const proj = [t / asp, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0];
    return mul(proj, view);
  }
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => { const l = Math.hypot(...a); return [a[0] / l, a[1] / l, a[2] / l]; };
  function mul(a, b) { const o = new Array(16).fill(0);
    for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) o[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
    return o; }
  function invert(m) { // 4x4 inverse (column-major), for picking
    const inv = new Array(16); const [a00, a01, a02, a03, a10, a11, a12, a13, a20, a21, a22, a23, a30, a31, a32, a33] = m;
    const b00 = a00 * a11 - a01 * a10, b01 = a00 * a12 - a02 * a10, b02 = a00 * a13 - a03 * a10, b03 = a01 * a12 - a02 * a11,
      b04 = a01 * a13 - a03 * a11, b05 = a02 * a13 - a03 * a12, b06 = a20 * a31 - a21 * a30, b07 = a20 * a32 - a22 * a30,
      b08 = a20 * a33 - a23 * a30, b09 = a21 * a32 - a22 * a31, b10 = a21 * a33 - a23 * a31, b11 = a22 * a33 - a23 * a32;
    const det = 1 / (b00 * b11 - b01 * b10 + b02 * b09 + b03 * b08 - b04 * b07 + b05 * b06);
    inv[0] = (a11 * b11 - a12 * b10 + a13 * b09) * det; inv[1] = (a02 * b10 - a01 * b11 - a03 * b09) * det;
    inv[2] = (a31 * b05 - a32 * b04 + a33 * b03) * det; inv[3] = (a22 * b04 - a21 * b05 - a23 * b03) * det;
    inv[4] = (a12 * b08 - a10 * b11 - a13 * b07) * det; inv[5] = (a00 * b11 - a02 * b08 + a03 * b07) * det;
    inv[6] = (a32 * b02 - a30 * b05 - a33 * b01) * det; inv[7] = (a20 * b05 - a22 * b02 + a23 * b01) * det;
    inv[8] = (a10 * b10 - a11 * b08 + a13 * b06) * det; inv[9] = (a01 * b08 - a00 * b10 - a03 * b06) * det;
    inv[10] = (a30 * b04 - a31 * b02 + a33 * b00) * det; inv[11] = (a21 * b02 - a20 * b04 - a23 * b00) * det;
    inv[12] = (a11 * b07 - a10 * b09 - a12 * b06) * det; inv[13] = (a00 * b09 - a01 * b07 + a02 * b06) * det;
    inv[14] = (a31 * b01 - a30 * b03 - a32 * b00) * det; inv[15] = (a20 * b03 - a21 * b01 + a22 * b00) * det;
    return inv; }

  // ---- state and controls ------------------------------------------------------------------
  const kinds = meta.live && !meta.distant_only ? ["directional", "point", "spot"] : ["directional"];
  const light = Object.assign({ kind: "directional", az: 30, el: 35, dist: 1.5, cutoff: 20, power: 0, colour: [1, 1, 1], envRot: 0 }, meta.default_light || {});
  const state = { exposure: 0, show: "radiance", specular: false };
  function syncControls() { // the controls as the state says (after setLight, installLight)
    const sel = $("light-kind");
    if (sel.options.length !== kinds.length) { sel.length = 0; for (const k of kinds) sel.add(new Option(k, k)); }
    sel.value = light.kind;
    for (const [id, key] of [["light-az", "az"], ["light-el", "el"], ["light-dist", "dist"], ["light-cutoff", "cutoff"],
      ["light-power", "power"], ["env-rot", "envRot"]]) $(id).value = light[key];
    $("show").value = state.show;
    $("dist-row").classList.toggle("hidden", !pointish());
    $("cutoff-row").classList.toggle("hidden", light.kind !== "spot");
    $("env-row").classList.toggle("hidden", light.kind !== "environment");
  }
  const shows = [["radiance", "relit object"], ...meta.maps.map((m) => [m.key, m.name])];
  for (const [k, label] of shows) $("show").add(new Option(label, k));
  $("title").textContent = meta.title; $("subtitle").textContent = meta.subtitle;
  if (meta.reference) { // a render's error map against its volpath reference, as render wrote it
    const r = meta.reference, f = (x) => (typeof x === "number" ? x.toFixed(3) : "–");
    $("reference-img").src = "data:image/png;base64," + r.png;
    $("reference-note").textContent = `reference | ours | FLIP, from ${r.file}: relative RMSE ${f(r.rel_rmse)}, ` +
      `FLIP over the object ${f(r.flip_mean_object)} (the reference's own noise ${f(r.reference_noise)}); light ${r.light || "?"}.`;
    $("reference").classList.remove("hidden");
  }
  $("specular-row").classList.add("hidden");
  const bind = (id, key, f) => { const el = $(id); el.value = f ? f.to(light[key]) : light[key];
    el.addEventListener("input", () => { light[key] = f ? f.from(el.value) : parseFloat(el.value); lightChanged(); }); };
  bind("light-az", "az"); bind("light-el", "el"); bind("light-dist", "dist"); bind("light-cutoff", "cutoff");
  bind("light-power", "power"); bind("env-rot", "envRot");
  $("light-colour").addEventListener("input", (e) => { const h = e.target.value;
    light.colour = [1, 3, 5].map((i) => Math.pow(parseInt(h.substr(i, 2), 16) / 255, 2.2)); lightChanged(); });
  $("light-kind").addEventListener("change", (e) => { light.kind = e.target.value; lightChanged(); });
  $("exposure").addEventListener("input", (e) => { state.exposure = parseFloat(e.target.value); draw(); });
  $("show").addEventListener("change", (e) => { state.show = e.target.value; showChanged(); });
  $("specular").addEventListener("change", (e) => { state.specular = e.target.checked; draw(); });

  function lightDirection() { // unit vector from the centre towards the light
    const a = light.az * Math.PI / 180, e = light.el * Math.PI / 180;
    return [Math.cos(e) * Math.cos(a), Math.cos(e) * Math.sin(a), Math.sin(e)];
  }
  function lightScale() { return Math.pow(2, light.power); }
  function lightCoefficients() { // L_{k,c} of a distant light (power and colour in), as vec4 [c][k / 4]
    const p = lightScale(), kq = meta.kq, out = new Float32Array(27 * 4);
    let coef;
    if (light.kind === "directional") {
      const y = shBasis(lightDirection(), bands);
      coef = (k, c) => y[k] * meta.directional_irradiance;
    } else {
      const r = shRotateZ(Float64Array.from(meta.env.coefficients.flat()), bands, light.envRot * Math.PI / 180);
      coef = (k, c) => r[k * 3 + c];
    }
    for (let c = 0; c < 3; c++) for (let k = 0; k < K; k++) out[(c * 9) * 4 + k] = coef(k, c) * p * light.colour[c];
    return out;
  }

  function showChanged() {
    const m = meta.maps.find((x) => x.key === state.show);
    if (state.show === "compare_diff") {
      $("legend").innerHTML = "viridis from 0 to 0.5: |B - A| / A per vertex under this light (mean of R, G, B)"; draw(); return;
    }
    if (m) {
      upload("a_map", decode(m.key), 1);
      $("legend").innerHTML = m.flags ? `<span style="color:#e63">red</span>: ${m.legend}` :
        `viridis from ${m.lo.toPrecision(3)} to ${m.hi.toPrecision(3)} ${m.unit}`;
    } else $("legend").textContent = "";
    draw();
  }

  // ---- live relight (server: point and spot lights) -----------------------------------------
  // While the light moves the server relights the reduced mesh's vertices only (a draft: the same
  // physics on fewer receivers); once it settles, every vertex.
  const stats = { latency: [], frames: 0, updates: 0, drafts: 0, pending: false, inFlight: false, waiters: [], lastMesh: 0 };
  const direct = { full: null, draft: null };   // the light each radiance buffer holds
  const pointish = () => light.kind === "point" || light.kind === "spot";
  const moving = () => performance.now() - lastChange < SETTLE_MS;
  function lightKey() { return JSON.stringify([light.kind, light.az, light.el, light.dist, light.cutoff]); }
  function satisfied() { const k = lightKey(); return direct.full === k || (moving() && meshes.length > 1 && direct.draft === k); }
  function requestRelight() {
    if (stats.inFlight) { stats.pending = true; return; }
    if (!pointish() || satisfied()) return;
    stats.inFlight = true; stats.pending = false;
    const key = lightKey(), draft = moving() && meshes.length > 1, eventT = lastEvent;
    const body = JSON.stringify({ kind: light.kind, direction: lightDirection(), distance: light.dist, cutoff: light.cutoff, draft });
    const sent = performance.now();
    fetch("relight", { method: "POST", body }).then((r) => {
      if (!r.ok) return r.text().then((t) => { throw new Error(t); });
      const timing = /dur=([0-9.]+)/.exec(r.headers.get("Server-Timing") || "");
      stats.serverMs = timing ? parseFloat(timing[1]) : null;
      return r.arrayBuffer();
    }).then((buf) => {
      const values = new Uint16Array(buf);
      stats.fetchMs = performance.now() - sent;
      if (draft) { gl.bindBuffer(gl.ARRAY_BUFFER, meshes[1].buf.a_direct); gl.bufferSubData(gl.ARRAY_BUFFER, 0, values); stats.drafts++; }
      else { upload("a_direct", values, 3); direct.full = key; }
      direct.draft = key; stats.updates++; $("status").textContent = "";
      shownEvent = eventT;
      if (!queued) frame(); // at once: waiting for the next animation frame would add up to 16 ms
    }).catch((e) => { $("status").textContent = "relight: " + e.message; })
      .finally(() => { stats.inFlight = false; if (stats.pending || !satisfied()) requestRelight(); });
  }
  let lastEvent = 0, shownEvent = null;   // when the light last changed; the change a new buffer shows
  function lightChanged() {
    lastEvent = performance.now();
    const distant = !pointish();
    syncControls();
    // a point or spot light is drawn when the server's radiance for it comes (a frame before shows nothing new)
    moved(distant || state.show !== "radiance" || !ready);
    requestRelight();
  }

  // ---- drawing -------------------------------------------------------------------------------
  let queued = false, lastChange = -1e9, settleTimer = null;
  const SETTLE_MS = 250;  // the full mesh again this long after the last move
  function draw() { if (!queued) { queued = true; requestAnimationFrame(frame); } }
  function moved(redraw = true) { // a light or camera change: the reduced mesh until things settle
    lastChange = performance.now(); clearTimeout(settleTimer);
    settleTimer = setTimeout(() => { draw(); requestRelight(); }, SETTLE_MS + 20);
    if (redraw) draw();
  }
  function frame() {
    queued = false;
    const distant = !pointish();
    const comparing = state.show.startsWith("compare_");  // distant lights only: point lights show A
    const mode = (state.show !== "radiance" && !comparing) || !ready ? 2 : distant ? 0 : 1;
    const key = lightKey(), lod = meshes.length > 1;
    // the reduced mesh while things move, and while only a draft of this light is at hand
    const useLod = lod && (moving() || (mode === 1 && direct.full !== key && direct.draft === key));
    const mesh = useLod ? meshes[1] : meshes[0];
    const d = lightDirection(), local = mode === 0 && light.kind === "directional";
    const shadowMvp = lightMvp(d);
    if (local && shadowKey !== JSON.stringify([d, mesh.n])) { renderShadow(mesh, shadowMvp); shadowKey = JSON.stringify([d, mesh.n]); }
    const w = canvas.clientWidth * devicePixelRatio | 0, h = canvas.clientHeight * devicePixelRatio | 0;
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.114, 0.122, 0.129, 1); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(prog); gl.bindVertexArray(mesh.vao);
    gl.uniform1i(U.u_local, local ? 1 : 0);
    if (local) {
      gl.uniformMatrix4fv(U.u_lightmvp, false, shadowMvp); gl.uniform1f(U.u_offset, 1.5 * size / SHADOW);
      gl.uniform1f(U.u_blur, 0.5 * meta.blur_mm / (size / 2));  // mm -> shadow-map uv (the map spans size)
      gl.uniform3fv(U.u_Edir, light.colour.map((c) => c * meta.directional_irradiance * lightScale()));
    }
    gl.uniformMatrix4fv(U.u_mvp, false, mvp()); gl.uniform3fv(U.u_eye, eye());
    gl.uniform1i(U.u_mode, mode);
    if (mode === 0) gl.uniform4fv(U.u_L, lightCoefficients());
    const p = lightScale();
    gl.uniform3fv(U.u_tint, light.colour.map((c) => c * p));
    gl.uniform1f(U.u_exposure, meta.exposure * Math.pow(2, state.exposure));
    const m = meta.maps.find((x) => x.key === state.show);
    gl.uniform1i(U.u_flags, m && m.flags ? 1 : 0); if (m) gl.uniform2f(U.u_range, m.lo, m.hi);
    const model = { compare_b: 1, compare_diff: 2 }[state.show] || 0;
    gl.uniform1i(U.u_model, model); gl.uniform3f(U.u_shift, 0, 0, 0);
    if (model === 2) gl.uniform2f(U.u_range, 0.0, 0.5);
    const spec = state.specular && meta.eta !== 1 && light.kind !== "environment";
    gl.uniform1i(U.u_spec, spec ? 1 : 0);
    gl.uniform3fv(U.u_lightdir, d); gl.uniform1i(U.u_lightkind, distant ? 0 : 1);
    gl.uniform3fv(U.u_lightpos, [C[0] + d[0] * light.dist * size, C[1] + d[1] * light.dist * size, C[2] + d[2] * light.dist * size]);
    gl.uniform1f(U.u_spec_e, light.kind === "directional" ? meta.directional_irradiance : meta.point_intensity / Math.pow(light.dist * size, 2));
    if (state.show === "compare_side") { // A to the left, B to the right, as the camera sees them
      const E = eye(), f = norm(sub(C, E)), r = norm(cross(f, [0, 0, 1])), d = 0.55 * size;
      gl.uniform3f(U.u_shift, -d * r[0], -d * r[1], -d * r[2]); gl.uniform1i(U.u_model, 0);
      gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_INT, 0);
      gl.uniform3f(U.u_shift, d * r[0], d * r[1], d * r[2]); gl.uniform1i(U.u_model, mode === 0 ? 1 : 0);
    }
    gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_INT, 0);
    stats.lastMesh = mesh.n;
    if (picked !== null) drawMarker();
    stats.frames++;
    if (shownEvent !== null) { stats.latency.push(performance.now() - shownEvent); shownEvent = null; }
    const shown = mode !== 1 || (useLod ? direct.draft === key : direct.full === key);
    if (shown) { const ws = stats.waiters; stats.waiters = []; for (const f of ws) f(); }
  }

  // ---- picking and the profile plot ----------------------------------------------------------
  let picked = null;
  const markerProg = gl.createProgram();
  gl.attachShader(markerProg, shader(gl.VERTEX_SHADER, `#version 300 es
    uniform mat4 u_mvp; uniform vec3 u_p; void main() { gl_Position = u_mvp * vec4(u_p, 1.0); gl_PointSize = 9.0; }`));
  gl.attachShader(markerProg, shader(gl.FRAGMENT_SHADER, `#version 300 es
    precision mediump float; out vec4 c; void main() { c = vec4(1.0, 0.3, 0.8, 1.0); }`));
  gl.linkProgram(markerProg);
  const markerVao = gl.createVertexArray();
  function drawMarker() {
    gl.useProgram(markerProg); gl.bindVertexArray(markerVao); gl.disable(gl.DEPTH_TEST);
    gl.uniformMatrix4fv(gl.getUniformLocation(markerProg, "u_mvp"), false, mvp());
    gl.uniform3fv(gl.getUniformLocation(markerProg, "u_p"), Array.from(position.subarray(picked * 3, picked * 3 + 3)));
    gl.drawArrays(gl.POINTS, 0, 1); gl.enable(gl.DEPTH_TEST);
  }
  function pick(px, py) { // the vertex nearest the first triangle under the pixel (Moller-Trumbore)
    const r = canvas.getBoundingClientRect(), x = (px - r.left) / r.width * 2 - 1, y = 1 - (py - r.top) / r.height * 2;
    const inv = invert(mvp()), un = (v) => { const o = [0, 0, 0, 0];
      for (let i = 0; i < 4; i++) for (let k = 0; k < 4; k++) o[i] += inv[k * 4 + i] * v[k]; return [o[0] / o[3], o[1] / o[3], o[2] / o[3]]; };
    const o = un([x, y, -1, 1]), dir = norm(sub(un([x, y, 1, 1]), o));
    let best = Infinity, tri = -1;
    for (let f = 0; f < F; f++) {
      const i0 = index[3 * f] * 3, i1 = index[3 * f + 1] * 3, i2 = index[3 * f + 2] * 3;
      const e1x = position[i1] - position[i0], e1y = position[i1 + 1] - position[i0 + 1], e1z = position[i1 + 2] - position[i0 + 2];
      const e2x = position[i2] - position[i0], e2y = position[i2 + 1] - position[i0 + 1], e2z = position[i2 + 2] - position[i0 + 2];
      const px_ = dir[1] * e2z - dir[2] * e2y, py_ = dir[2] * e2x - dir[0] * e2z, pz_ = dir[0] * e2y - dir[1] * e2x;
      const det = e1x * px_ + e1y * py_ + e1z * pz_;
      if (Math.abs(det) < 1e-12) continue;
      const tx = o[0] - position[i0], ty = o[1] - position[i0 + 1], tz = o[2] - position[i0 + 2];
      const u = (tx * px_ + ty * py_ + tz * pz_) / det; if (u < 0 || u > 1) continue;
      const qx = ty * e1z - tz * e1y, qy = tz * e1x - tx * e1z, qz = tx * e1y - ty * e1x;
      const v = (dir[0] * qx + dir[1] * qy + dir[2] * qz) / det; if (v < 0 || u + v > 1) continue;
      const t = (e2x * qx + e2y * qy + e2z * qz) / det;
      if (t > 0 && t < best) { best = t; tri = f; }
    }
    if (tri < 0) return null;
    const hit = [o[0] + best * dir[0], o[1] + best * dir[1], o[2] + best * dir[2]];
    let vbest = -1, dbest = Infinity;
    for (let q = 0; q < 3; q++) { const i = index[3 * tri + q];
      const dd = Math.hypot(position[3 * i] - hit[0], position[3 * i + 1] - hit[1], position[3 * i + 2] - hit[2]);
      if (dd < dbest) { dbest = dd; vbest = i; } }
    return vbest;
  }
  const prof = meta.profiles;
  const profPoints = prof ? decode("profile_points") : null;     // (N, 3) float32
  const profModel = prof ? decode("profile_model") : null;       // (N, R, 3) float32, mm^-2
  const profData = prof && prof.measured ? decode("profile_measured") : null;
  const profTruth = prof && prof.truth ? decode("profile_truth") : null;
  function nearestPoint(v) {
    let best = -1, bd = Infinity;
    for (let i = 0; i < prof.count; i++) { const d = Math.hypot(profPoints[3 * i] - position[3 * v],
      profPoints[3 * i + 1] - position[3 * v + 1], profPoints[3 * i + 2] - position[3 * v + 2]);
      if (d < bd) { bd = d; best = i; } }
    return [best, bd];
  }
  function plotProfile(v) {
    const cv = $("profile"), g = cv.getContext("2d"), W = cv.width, H = cv.height;
    g.fillStyle = "#1d1f21"; g.fillRect(0, 0, W, H);
    if (!prof) { $("profile-note").textContent = "This model carries no profiles."; return; }
    const [i, dist] = nearestPoint(v), R = prof.radii_mm.length, rr = prof.radii_mm;
    const vals = [];
    for (let j = 0; j < R * 3; j++) { vals.push(profModel[i * R * 3 + j]); if (profData) vals.push(profData[i * R * 3 + j]);
      if (profTruth) vals.push(profTruth[i * R * 3 + j]); }
    const pos = vals.filter((x) => x > 0 && isFinite(x));
    const hi = Math.log10(Math.max(...pos)), lo = Math.max(Math.log10(Math.min(...pos)), hi - 6);
    const x0 = 70, y0 = 20, x1 = W - 14, y1 = H - 50;
    const X = (r) => x0 + (Math.log10(r) - Math.log10(rr[0])) / (Math.log10(rr[R - 1]) - Math.log10(rr[0])) * (x1 - x0);
    const Y = (f) => y1 - (Math.log10(f) - lo) / (hi - lo) * (y1 - y0);
    g.strokeStyle = "#666"; g.strokeRect(x0, y0, x1 - x0, y1 - y0);
    g.fillStyle = "#aaa"; g.font = "20px system-ui";
    g.fillText("r [mm] (log)", (x0 + x1) / 2 - 50, H - 12); g.save(); g.translate(22, (y0 + y1) / 2 + 70); g.rotate(-Math.PI / 2);
    g.fillText("R_d [mm^-2] (log)", 0, 0); g.restore();
    g.fillText(rr[0].toPrecision(2), x0 - 10, y1 + 22); g.fillText(rr[R - 1].toPrecision(2), x1 - 40, y1 + 22);
    g.fillText("1e" + hi.toFixed(1), 4, y0 + 12); g.fillText("1e" + lo.toFixed(1), 4, y1);
    const cols = ["#f55", "#5d5", "#59f"];
    for (let c = 0; c < 3; c++) {
      g.strokeStyle = cols[c]; g.lineWidth = 2.5; g.beginPath(); let started = false;
      for (let j = 0; j < R; j++) { const f = profModel[(i * R + j) * 3 + c]; if (!(f > 0)) continue;
        const yy = Math.max(Math.min(Y(f), y1), y0);
        if (!started) { g.moveTo(X(rr[j]), yy); started = true; } else g.lineTo(X(rr[j]), yy); }
      g.stroke();
      if (profData) { g.fillStyle = cols[c];
        for (let j = 0; j < R; j++) { const f = profData[(i * R + j) * 3 + c]; if (!(f > 0) || Y(f) > y1 || Y(f) < y0) continue;
          g.beginPath(); g.arc(X(rr[j]), Y(f), 4, 0, 2 * Math.PI); g.fill(); } }
      if (profTruth) { g.strokeStyle = cols[c]; g.lineWidth = 1.5;
        for (let j = 0; j < R; j++) { const f = profTruth[(i * R + j) * 3 + c]; if (!(f > 0) || Y(f) > y1 || Y(f) < y0) continue;
          const x = X(rr[j]), y = Y(f); g.beginPath(); g.moveTo(x - 4, y - 4); g.lineTo(x + 4, y + 4); g.moveTo(x - 4, y + 4); g.lineTo(x + 4, y - 4); g.stroke(); } }
    }
    $("profile-note").textContent = `vertex ${v}: incident point ${i} (${dist.toFixed(1)} mm away); lines: the fit's ring means` +
      (profData ? ", dots: the measured ring means" : " (the data set is not at hand: no measured rings)") +
      (profTruth ? ", crosses: the truth's (an independent acquisition)" : "") + "; R, G, B.";
  }

  // ---- mouse: orbit, light drag, zoom, click --------------------------------------------------
  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => { drag = { x: e.clientX, y: e.clientY, light: e.button === 2 || e.shiftKey, moved: 0 };
    canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y; drag.x = e.clientX; drag.y = e.clientY; drag.moved += Math.abs(dx) + Math.abs(dy);
    if (drag.light) { light.az = ((light.az - dx * 0.5 + 540) % 360) - 180; light.el = Math.max(-89, Math.min(89, light.el + dy * 0.5));
      $("light-az").value = light.az; $("light-el").value = light.el; lightChanged(); }
    else { cam.az -= dx * 0.4; cam.el = Math.max(-89, Math.min(89, cam.el + dy * 0.4)); moved(); }
  });
  canvas.addEventListener("pointerup", (e) => {
    if (drag && drag.moved < 4 && !drag.light) { const v = pick(e.clientX, e.clientY); if (v !== null) { picked = v; plotProfile(v); draw(); } }
    drag = null; });
  canvas.addEventListener("wheel", (e) => { e.preventDefault(); cam.dist *= Math.exp(e.deltaY * 0.001); moved(); }, { passive: false });
  window.addEventListener("resize", draw);

  const onePixel = new Uint8Array(4);
  function settle() { gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, onePixel); } // waits for the frame

  // ---- for scripts and tests: set the light and wait for the frame that shows it ---------------
  window.TL = {
    meta, stats, light, cam,
    setLight(changes) {
      Object.assign(light, changes); syncControls();
      return new Promise((resolve) => { stats.waiters.push(() => { settle(); resolve(performance.now()); }); lightChanged(); });
    },
    drawNow() { const t = performance.now(); frame(); settle(); return performance.now() - t; },
    // frames per second while the light turns (or the camera, ``what = "camera"``) for ``ms``
    spin(ms, what, full) {
      return new Promise((resolve) => {
        const t0 = performance.now(); let n = 0;
        const step = (now) => {
          if (what === "camera") cam.az += 2; else { light.az = ((light.az + 3 + 180) % 360) - 180; if (light.kind === "environment") light.envRot = light.az; }
          lastChange = full ? -1e9 : now; frame(); n++;
          if (now - t0 < ms) requestAnimationFrame(step); else { settle(); resolve(n / ((performance.now() - t0) / 1000)); }
        };
        requestAnimationFrame(step);
      });
    },
    setShow(key) { state.show = key; syncControls(); showChanged(); },
    // a drag: the light turned a little every ``everyMs`` (as pointer events come) for ``ms``; returns the
    // updates shown per second and each update's time from its event to its frame
    drag(ms, everyMs = 16, step = 1) {
      return new Promise((resolve) => {
        const u0 = stats.updates, t0 = performance.now(); stats.latency = [];
        const timer = setInterval(() => {
          light.az = ((light.az + step + 180) % 360) - 180; syncControls(); lightChanged();
          if (performance.now() - t0 > ms) {
            clearInterval(timer);
            resolve({ updates_per_s: (stats.updates - u0) / ((performance.now() - t0) / 1000), latency_ms: stats.latency.slice() });
          }
        }, everyMs);
      });
    },
    get ready() { return ready; },
    pickAt(x, y) { const v = pick(x, y); if (v !== null) { picked = v; plotProfile(v); draw(); } return v; },
    frame() { return new Promise((resolve) => { stats.waiters.push(() => { settle(); resolve(performance.now()); }); draw(); }); },
  };
  syncControls(); showChanged();
  if (D.arrays.transfer) installLight({}, D.arrays);   // a page: everything is here
  else {                                               // served live: the relighting comes when prepared
    state.show = meta.maps[0].key; syncControls(); showChanged();  // a map meanwhile
    $("status").textContent = meta.status || "preparing the relighting…";
    const poll = () => fetch("light.json").then((r) => r.json()).then((j) => {
      if (j.meta) installLight(j.meta, j.arrays);
      else if (j.failed) $("status").textContent = "the relighting failed: " + j.failed;
      else { $("status").textContent = j.pending; setTimeout(poll, 700); }
    }).catch(() => setTimeout(poll, 1500));
    poll();
  }
})();
