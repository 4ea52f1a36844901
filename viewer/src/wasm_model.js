// One model's WebAssembly module (wasm/wlx_<model>.js, built from viewer/wasm/viewer_module.cpp):
// its tables, the closed-form IK, the forward kinematics, the closure residual and the bodies'
// centres of mass. Buffers are allocated once in the module's heap and reused for every call.

export class WasmModel {
  static async load(name, loadScript) {
    if (!/^[A-Za-z][A-Za-z0-9_]*$/.test(name)) throw new Error(`model name '${name}': a model's name is an identifier (letters, digits, _)`);
    await loadScript(`wasm/wlx_${name}.js`);
    const factory = window[`wlxModule_${name}`];
    if (typeof factory !== 'function') throw new Error(`wasm/wlx_${name}.js did not define wlxModule_${name}`);
    return new WasmModel(await factory());
  }

  constructor(module) {
    this.m = module;
    this.info = JSON.parse(module.UTF8ToString(module._wlx_model_info_json()));
    const n = this.info.coordinates.length, f = this.info.frames.length, b = this.info.bodies.length;
    const doubles = (count) => module._malloc(8 * count);
    this.buf = {
      inputs: doubles(this.info.inputCount), s: doubles(n), sOut: doubles(n),
      positions: doubles(3 * f), rotations: doubles(9 * f), com: doubles(3 * b),
      branches: module._malloc(4 * this.info.limbs.length),
    };
  }

  heap(pointer, count) { return new Float64Array(this.m.HEAPF64.buffer, pointer, count); }  // views die when memory grows: make them per call

  // { ok: true, s } or { ok: false, message } (the message `wlx ik` prints for the same inputs).
  solve(inputs, branches) {
    const { m, buf, info } = this;
    this.heap(buf.inputs, info.inputCount).set(inputs.subarray ? inputs.subarray(0, info.inputCount) : inputs.slice(0, info.inputCount));
    new Int32Array(m.HEAP32.buffer, buf.branches, info.limbs.length).set(branches);
    if (!m._wlx_solve_ik(buf.inputs, buf.branches, buf.sOut)) return { ok: false, message: m.UTF8ToString(m._wlx_last_error()) };
    return { ok: true, s: Float64Array.from(this.heap(buf.sOut, info.coordinates.length)) };
  }

  setS(s) { this.heap(this.buf.s, this.info.coordinates.length).set(s); }

  forwardKinematics(s) {
    const { m, buf, info } = this;
    this.setS(s);
    m._wlx_forward_kinematics(buf.s, buf.positions, buf.rotations);
    const f = info.frames.length;
    return { positions: Float64Array.from(this.heap(buf.positions, 3 * f)), rotations: Float64Array.from(this.heap(buf.rotations, 9 * f)) };
  }

  closureResidual(s) {
    this.setS(s);
    return this.m._wlx_closure_residual(this.buf.s);
  }

  bodyCentres(s) {
    this.setS(s);
    this.m._wlx_body_centres(this.buf.s, this.buf.com);
    return Float64Array.from(this.heap(this.buf.com, 3 * this.info.bodies.length));
  }
}
