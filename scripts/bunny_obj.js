// Writes the Stanford bunny of the npm package `bunny` (positions/cells arrays) as examples/bunny.obj for the
// default scene. Generated at setup rather than committed: the data belongs to the npm package.
// Usage: node scripts/bunny_obj.js [OUT.obj]
const fs = require('fs');
const path = require('path');
const bunny = require(path.join(__dirname, '..', 'node_modules', 'bunny'));
const out = process.argv[2] || path.join(__dirname, '..', 'examples', 'bunny.obj');
const lines = ['# Stanford bunny (Stanford 3D Scanning Repository), from the npm package bunny'];
for (const p of bunny.positions) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of bunny.cells) lines.push(`f ${c[0] + 1} ${c[1] + 1} ${c[2] + 1}`);
const tmp = out + '.tmp';
fs.writeFileSync(tmp, lines.join('\n') + '\n');
fs.renameSync(tmp, out);
