#!/usr/bin/env node
// SPDX-License-Identifier: MIT
/*
 * What the Khronos glTF-Validator (npm package gltf-validator) says about glTF files: one JSON line per
 * file, so that tests/gltf/lies.py can set the validator's rules beside pvsbake's own checks.
 *
 *     {"file": F, "validator": VERSION, "errors": [CODE...], "warnings": [CODE...],
 *      "messages": [{"code", "severity", "pointer", "message"}...]}
 *
 * errors and warnings hold each code once, in the order of its first message (severity 0 and 1);
 * messages holds every issue the validator raised, hints and information included (severity 2 and 3).
 * A .gltf file's external buffers are read from beside it.
 *
 * The validator is found in the folder that --validator names; without it, as the module
 * 'gltf-validator' (NODE_PATH), then in /opt/pvsbake-npm/node_modules/gltf-validator, where
 *     npm install --prefix /opt/pvsbake-npm gltf-validator
 * puts it.
 *
 * usage: node tests/gltf/validate.js [--validator DIR] FILE...
 * Exit 0 when every file was validated, whatever the validator found; 77 when the validator is not
 * installed; 1 when a file could not be read or the validator gave up on it (its line then holds
 * "failure" instead of the issues); 2 on a usage error.
 */
'use strict';

const fs = require('fs');
const path = require('path');

const DEFAULT_VALIDATOR = '/opt/pvsbake-npm/node_modules/gltf-validator';
const NOT_INSTALLED = 77;
const SEVERITY_ERROR = 0;
const SEVERITY_WARNING = 1;

function usage(message) {
    process.stderr.write(`validate.js: ${message}\nusage: node validate.js [--validator DIR] FILE...\n`);
    process.exit(2);
}

function parseArgs(argv) {
    const args = { validator: null, files: [] };
    for (let i = 0; i < argv.length; i++) {
        if (argv[i] === '--validator') {
            if (i + 1 >= argv.length) usage('--validator needs a folder');
            args.validator = argv[++i];
        } else if (argv[i] === '-h' || argv[i] === '--help') {
            process.stdout.write('usage: node validate.js [--validator DIR] FILE...\n');
            process.exit(0);
        } else {
            args.files.push(argv[i]);
        }
    }
    if (args.files.length === 0) usage('no file given');
    return args;
}

function isMissing(err, request) {
    return err.code === 'MODULE_NOT_FOUND' && String(err.message).includes(request);
}

/** The validator module: from DIR when given, else as 'gltf-validator' (NODE_PATH), else the default. */
function loadValidator(dir) {
    const tries = dir ? [path.resolve(dir)] : ['gltf-validator', DEFAULT_VALIDATOR];
    for (const request of tries) {
        try {
            return require(request);
        } catch (err) {
            if (!isMissing(err, request)) throw err;
        }
    }
    process.stderr.write(`validate.js: the glTF-Validator is not installed (looked for ${tries.join(', ')}); ` +
        'install it with: npm install --prefix /opt/pvsbake-npm gltf-validator\n');
    process.exit(NOT_INSTALLED);
}

function firstCodes(messages, severity) {
    return [...new Set(messages.filter((m) => m.severity === severity).map((m) => m.code))];
}

async function validateFile(validator, file) {
    const options = {
        uri: path.basename(file),
        maxIssues: 0,
        writeTimestamp: false,
        externalResourceFunction: (uri) =>
            fs.promises.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)))
                .then((data) => new Uint8Array(data)),
    };
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), options);
    const messages = report.issues.messages.map((m) => ({
        code: m.code,
        severity: m.severity,
        pointer: m.pointer === undefined ? null : m.pointer,
        message: m.message,
    }));
    return {
        file,
        validator: validator.version(),
        errors: firstCodes(messages, SEVERITY_ERROR),
        warnings: firstCodes(messages, SEVERITY_WARNING),
        messages,
    };
}

async function main() {
    const args = parseArgs(process.argv.slice(2));
    const validator = loadValidator(args.validator);
    let status = 0;
    for (const file of args.files) {
        let line;
        try {
            line = await validateFile(validator, file);
        } catch (err) {
            line = { file, failure: String(err && err.message ? err.message : err) };
            status = 1;
        }
        process.stdout.write(JSON.stringify(line) + '\n');
    }
    process.exitCode = status;
}

main();
