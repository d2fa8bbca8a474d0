// The page: starts the engine (WebAssembly) on the canvas, has the worker build the world
// (so the page never freezes) and hands it over, and loads heightmap files picked or dropped.
import init, { start, deliver_world, page_state, capture } from './pkg/rayterra_web.js';

const $ = (id) => document.getElementById(id);

function showError(message) {
  const box = $('error');
  box.textContent = message;
  box.hidden = false;
  $('progress').hidden = true;
}

function showProgress(fraction, stage) {
  $('progress').hidden = false;
  $('progress-bar').value = fraction;
  $('progress-text').textContent = `building the world: ${stage} ${Math.round(fraction * 100)}%`;
}

async function main() {
  try {
    await init();
  } catch (error) {
    showError(`This browser cannot run the page's WebAssembly: ${error}`);
    return;
  }
  // For people and for the browser test: what the page is doing, and the next frame read back.
  window.rayterra = { state: page_state, capture };
  let options;
  try {
    const query = new URLSearchParams(location.search);
    const size = query.get('size');
    if (size) {
      // A fixed canvas size (e.g. to compare with `rayterra terrain --screenshot --size`).
      const [width, height] = size.split(/x/i).map(Number);
      if (width > 0 && height > 0) {
        const canvas = $('terrain');
        canvas.classList.add('fixed');
        canvas.style.width = `${width / devicePixelRatio}px`;
        canvas.style.height = `${height / devicePixelRatio}px`;
      }
    }
    options = start(location.search);
  } catch (error) {
    showError(error.message ?? String(error));
    return;
  }

  const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  let building = false;
  worker.onmessage = ({ data }) => {
    switch (data.type) {
      case 'progress':
        showProgress(data.fraction, data.stage);
        break;
      case 'world':
        building = false;
        try {
          deliver_world(data.layers, data.description);
          $('progress').hidden = true;
          $('error').hidden = true;
        } catch (error) {
          showError(error.message ?? String(error));
        }
        break;
      case 'error':
        building = false;
        showError(data.message);
        break;
    }
  };
  worker.onerror = (event) => {
    building = false;
    showError(`The world could not be built: ${event.message ?? 'the worker stopped'}`);
  };
  const build = (message, transfer = []) => {
    if (building) {
      showError('A world is still being built; try again when it is done.');
      return;
    }
    building = true;
    $('error').hidden = true;
    showProgress(0, 'starting');
    worker.postMessage(message, transfer);
  };
  build({ type: 'generate', seed: options.seed, grid: options.grid });

  const load = async (file) => {
    if (!file) return;
    const bytes = await file.arrayBuffer();
    build({ type: 'heightmap', name: file.name, bytes, seed: options.seed }, [bytes]);
  };
  $('file').addEventListener('change', (event) => load(event.target.files[0]));
  // A heightmap dropped anywhere on the page.
  const hud = $('hud');
  document.body.addEventListener('dragover', (event) => {
    event.preventDefault();
    hud.classList.add('dropping');
  });
  document.body.addEventListener('dragleave', () => hud.classList.remove('dropping'));
  document.body.addEventListener('drop', (event) => {
    event.preventDefault();
    hud.classList.remove('dropping');
    load(event.dataTransfer.files[0]);
  });
}

main();
