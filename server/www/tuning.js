// The "Tuning (on the server)" box: one `tune` request of the method and
// objective chosen (or --robust), its progress, and its gains made the
// design and pinned.
import {fmt} from './metrics.js';

// ctx: { pidlab, state, $, spec, ask, rawSend, showForm, evaluated, pin }.
export function initTuning(ctx) {
  const {pidlab, state, $} = ctx;
  let running = false;

  function progress(m) {
    if (!running) return;
    $('tune-status').textContent = 'tuning: ' + m.evaluations + ' evaluations, best objective ' + fmt(m.best);
  }

  function tuningSpec(options) {
    const s = ctx.spec();
    for (const k of ['gains', 'monte_carlo', 'spread']) delete s[k];  // evaluate's keys, not a tuning's
    if (options.robust) s.robust = true;
    for (const k
             of ['method', 'objective', 'bounds', 'max_evals', 'max_iter', 'max_ms', 'max_mt',
                 'max_noise_gain', 'min_phase_margin', 'refine'])
      if (options[k] !== undefined) s[k] = options[k];
    return s;
  }

  async function tune(options) {
    const s = tuningSpec(options || {});
    $('tune-status').textContent = 'tuning: started';
    running = true;
    try {
      const reply = await ctx.ask({type: 'tune', spec: s});
      running = false;
      pidlab.lastTune = reply.result;
      const g = reply.result.gains;
      $('tune-status').textContent = 'tuned: objective ' + fmt(reply.result.objective) + ', gains ' +
          [g.kp, g.ki, g.kd].map(fmt).join(', ') +
          (reply.result.refine ?
               ', Ceres: ' + (reply.result.refine.verdict || JSON.stringify(reply.result.refine)) :
               '');
      state.kp = g.kp;
      state.ki = g.ki;
      state.kd = g.kd;
      if (g.tf > 0) state.derivative_filter = g.tf;
      ctx.showForm();
      await ctx.evaluated();
      ctx.pin('tuned ' + (s.robust ? '--robust ' : '') + [g.kp, g.ki, g.kd].map(fmt).join('/'));
      return reply.result;
    } catch (e) {
      running = false;
      $('tune-status').textContent = 'tuning: ' + e.message;
      throw e;
    }
  }

  function formOptions() {
    if ($('tune-robust').checked) return {robust: true};
    return {method: $('tune-method').value, objective: $('tune-objective').value};
  }

  pidlab.tune = tune;
  pidlab.cancelTune = () => ctx.rawSend({type: 'tune_cancel'});
  $('tune-button').addEventListener('click', () => tune(formOptions()).catch(() => {}));
  $('tune-cancel').addEventListener('click', () => pidlab.cancelTune());
  return {progress};
}
