// Pinned designs (drawn beside the current one, compared in a table) and the
// paper's designs (Tables II-VI), in the collapsed "Paper" section.
import {fmt, renderDiff} from './metrics.js';

// ctx: { pidlab, state, $, setDesign, rebuildPlots, ask, setStatus }.
export function initPins(ctx) {
  const {pidlab, state, $} = ctx;

  function diff() {
    renderDiff($('diff-table'), pidlab.lastResult, pidlab.pinned);
  }

  function render() {
    const listEl = $('pinned-list');
    listEl.textContent = '';
    pidlab.pinned.forEach((p, i) => {
      const div = document.createElement('div');
      div.className = 'pinned-design';
      const name = document.createElement('span');
      name.textContent = p.label + ' ';
      const load = document.createElement('button');
      load.textContent = 'load';
      load.addEventListener('click', () => {
        Object.assign(state, p.state || {});
        ctx.setDesign({plant: p.result.plant === 'model' ? state.plant : p.spec.plant, gains: p.spec.gains});
      });
      const drop = document.createElement('button');
      drop.textContent = 'unpin';
      drop.addEventListener('click', () => {
        pidlab.pinned.splice(i, 1);
        render();
        ctx.rebuildPlots();
      });
      div.append(name, load, drop);
      listEl.append(div);
    });
    diff();
  }

  function pin(label) {
    if (!pidlab.lastResult) return null;
    const r = pidlab.lastResult;
    const g = r.gains;
    const design = {
      label: label ||
          'P' + (pidlab.pinned.length + 1) + ' ' + r.plant + ' ' + [g.kp, g.ki, g.kd].map(fmt).join('/'),
      spec: r.spec,
      result: r,
      series: pidlab.lastSeries,
    };
    pidlab.pinned.push(design);
    render();
    ctx.rebuildPlots();
    return design;
  }

  // The paper's designs: buttons in the collapsed "Paper" section.
  async function loadPaperDesigns() {
    try {
      const reply = await ctx.ask({type: 'paper_designs'});
      pidlab.paperDesigns = reply.designs;
      for (const d of reply.designs) {
        const b = document.createElement('button');
        b.className = 'paper-design';
        b.textContent = 'Table ' + d.table + ' ' + d.plant + ' ' + d.method +
            (d.disturbance_amplitude ? ' ±' + d.disturbance_amplitude : '');
        b.addEventListener('click', () => ctx.setDesign({plant: d.plant, gains: d.gains}));
        $('paper-designs').append(b);
      }
    } catch (e) {
      ctx.setStatus('paper designs: ' + e.message);
    }
  }

  return {pin, render, diff, loadPaperDesigns};
}
