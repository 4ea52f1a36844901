// Bundles the page (src/ with three.js) into one classic script, dist/viewer.js, and copies
// viewer.html beside it: classic scripts load from file://, ES modules do not.
// Usage: NODE_PATH=<node_modules> node build.cjs OUT_DIR MODEL...   (the models whose
// wasm/wlx_<model>.js the CMake build makes). CommonJS, so that NODE_PATH finds the packages
// that `npm ci` installed in the build tree (ES module imports ignore NODE_PATH).
const esbuild = require('esbuild');
const { copyFileSync, mkdirSync, renameSync } = require('node:fs');
const { join } = require('node:path');

const here = __dirname;
const [outDir, ...models] = process.argv.slice(2);
if (!outDir || models.length === 0 || models.some((m) => !/^[a-z][a-z0-9_]*$/.test(m))) {
  console.error('usage: node build.cjs OUT_DIR MODEL... (model names: lower-case letters, digits, _)');
  process.exit(2);
}
mkdirSync(outDir, { recursive: true });
// Written under temporary names and renamed into place, so a file under its own name is complete.
esbuild.build({
  entryPoints: [join(here, 'src/main.js')],
  bundle: true,
  format: 'iife',
  target: 'es2020',
  minify: true,
  legalComments: 'eof',  // keeps three.js' licence notice
  banner: { js: `window.WLX_VIEWER_MODELS = ${JSON.stringify(models)};` },
  outfile: join(outDir, 'viewer.js.tmp'),
  logLevel: 'warning',
  nodePaths: (process.env.NODE_PATH || '').split(':').filter(Boolean),
}).then(() => {
  renameSync(join(outDir, 'viewer.js.tmp'), join(outDir, 'viewer.js'));
  copyFileSync(join(here, 'viewer.html'), join(outDir, 'viewer.html.tmp'));
  renameSync(join(outDir, 'viewer.html.tmp'), join(outDir, 'viewer.html'));
}, (error) => {
  console.error(`viewer bundle: ${error.message}`);
  process.exit(1);
});
