// Validate glTF files with the Khronos validator (npm gltf-validator); prints one JSON object:
// {file: {numErrors, numWarnings, messages: [...]}}. Usage: node validate_gltf.cjs FILE...
// The validator is found through NODE_PATH (./dev setup installs it under .venv/node).
const fs = require("fs");
const validator = require("gltf-validator");

(async () => {
  const out = {};
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: file,
      maxIssues: 50,
    });
    out[file] = {
      numErrors: report.issues.numErrors,
      numWarnings: report.issues.numWarnings,
      messages: report.issues.messages.map((m) => `${m.severity} ${m.code} ${m.pointer || ""}: ${m.message}`),
    };
  }
  console.log(JSON.stringify(out, null, 1));
})();
