// Runs the Khronos glTF validator (npm gltf-validator) on each file given; prints one line per
// file and every error, and exits 1 when any file has an error.
// Usage: node validate.cjs NODE_MODULES_DIR FILE.glb...
const fs = require('fs');
const path = require('path');
const validator = require(path.join(process.argv[2], 'gltf-validator'));

(async () => {
  let bad = 0;
  for (const file of process.argv.slice(3)) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {uri: path.basename(file), maxIssues: 50});
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ` +
                `${i.numHints} hints; ${report.info.totalVertexCount} vertices, ` +
                `${report.info.totalTriangleCount} triangles, ${report.info.maxUVs} UV sets`);
    for (const m of i.messages)
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code}: ${m.message} ${m.pointer || ''}`);
    if (i.numErrors > 0) bad++;
  }
  process.exit(bad ? 1 : 0);
})().catch((e) => {
  console.error(e);
  process.exit(2);
});
