const puppeteer = require('puppeteer-core');
(async () => {
const [dir, query = ''] = process.argv.slice(2);
const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--allow-file-access-from-files'] });
const page = await browser.newPage();
await page.setViewport({ width: 1280, height: 800 });
page.on('console', (m) => console.log('console', m.type(), m.text()));
page.on('pageerror', (e) => console.log('pageerror', e.message));
await page.goto(`file://${dir}/viewer.html${query}`);
await page.evaluate(() => window.wlxViewer.ready).catch((e) => console.log('ready failed', e.message));
await new Promise((r) => setTimeout(r, 500));
console.log(await page.evaluate(() => JSON.stringify({ msg: wlxViewer.api.message(), px: wlxViewer.api.paintedPixels(), h: wlxViewer.api.handles() })));
await page.screenshot({ path: '/tmp/smoke.png' });
await browser.close();
})();
