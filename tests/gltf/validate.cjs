// Runs the Khronos glTF-Validator on each file named on the command line and prints its report's
// messages; exits 1 when any file has an error (warnings and infos are printed, not failed on), 2 when
// the validator cannot be loaded or a file cannot be read.
//
// The validator is the `gltf-validator` npm package (its JavaScript API, `validateBytes`; it has no
// command line). anima's tests were written against gltf-validator 2.0.0-dev.3.10. Run as
//   NODE_PATH=<folder>/node_modules node tests/gltf/validate.cjs file.glb...
// where `npm install --prefix <folder> gltf-validator` was run (the tests set NODE_PATH from
// ANIMA_GLTF_VALIDATOR). CommonJS, so that NODE_PATH resolves the package.
'use strict';

const fs = require('fs');
const path = require('path');

let validator;
try {
    validator = require('gltf-validator');
} catch (e) {
    console.error(`validate.cjs: cannot load gltf-validator (${e.message}); run npm install gltf-validator and set NODE_PATH`);
    process.exit(2);
}

const SEVERITY = ['error', 'warning', 'info', 'hint'];

async function main(files) {
    if (files.length === 0) {
        console.error('usage: node validate.cjs FILE.glb...');
        return 2;
    }
    console.log(`gltf-validator ${validator.version()}`);
    let failed = false;
    for (const file of files) {
        let bytes;
        try {
            bytes = new Uint8Array(fs.readFileSync(file));
        } catch (e) {
            console.error(`${file}: ${e.message}`);
            return 2;
        }
        const report = await validator.validateBytes(bytes, {
            uri: path.basename(file),
            maxIssues: 0,
            writeTimestamp: false,
        });
        const i = report.issues;
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
        for (const m of i.messages) {
            console.log(`  ${SEVERITY[m.severity] ?? m.severity} ${m.code} at ${m.pointer ?? m.offset ?? '-'}: ${m.message}`);
        }
        if (i.numErrors > 0) {
            failed = true;
        }
    }
    return failed ? 1 : 0;
}

main(process.argv.slice(2)).then(
    (code) => process.exit(code),
    (e) => {
        console.error(`validate.cjs: ${e}`);
        process.exit(2);
    },
);
