// SPDX-License-Identifier: Apache-2.0
// Plays an `impulse export flipbook` PNG atlas at its sidecar's fps on a plane whose UVs repeat
// the cell RxR, as an engine tiles a material (README.md beside this file; the atlas layout and
// the sidecar's keys are docs/export.md "Flipbook").
//
// Sampling is done in the shader, in the cell's own texels, so that no tap ever reaches a
// neighbouring cell of the atlas (the classic flipbook seam: bilinear filtering across a cell's
// edge mixes in another frame):
//   wrap  (default for a tileable atlas) bilinear with its 2x2 taps wrapped inside the cell, which
//         is what GL_REPEAT does to a single tileable texture: the tile's last texel blends into
//         its own first one, so the border is filtered as any line inside;
//   clamp (default otherwise) hardware bilinear with the position clamped half a texel inside the
//         cell (the usual inset): no bleed, but the edge texel is held for half a texel;
//   naive the cell's full extent sampled with hardware bilinear and no inset: the bug, kept so a
//         test can show that it is seen.
// No mipmaps: an atlas's coarser levels average neighbouring cells together, and the jump of the
// wrapped coordinate at each tile border would make the hardware pick the coarsest level along it.
// The PNG's bytes go to the screen unchanged (no colour-space conversion on upload or output), so
// a held frame at one texel per pixel shows the atlas's cell exactly.
import * as THREE from "three";

const body = document.body;

class PageError extends Error {}

function fail(message) {
    throw new PageError(message);
}

function showError(message) {
    body.dataset.error = message;
    document.getElementById("error").textContent = message;
}

/// A whole number in [lo, hi] from the query, or `fallback` when absent.
function queryInt(params, key, fallback, lo, hi) {
    if (!params.has(key)) return fallback;
    const text = params.get(key);
    const value = Number(text);
    if (!/^-?\d+$/.test(text) || value < lo || value > hi)
        fail(`?${key}=${text}: expected a whole number in [${lo}, ${hi}]`);
    return value;
}

/// The texel offset "X" or "X,Y" (the picture moved by a fraction of a texel: pixel centres off
/// the texel centres, as under any moving camera).
function queryOffset(params) {
    if (!params.has("offset")) return [0, 0];
    const text = params.get("offset");
    const parts = text.split(",").map(Number);
    if (parts.length > 2 || parts.some((v) => !Number.isFinite(v)))
        fail(`?offset=${text}: expected X or X,Y in texels, e.g. 0.5`);
    return parts.length === 1 ? [parts[0], parts[0]] : parts;
}

/// The sidecar's whole number at `path` ("layout.rows"), >= lo.
function sidecarInt(name, json, path, lo) {
    const value = path.split(".").reduce((o, k) => (o === undefined || o === null ? undefined : o[k]), json);
    if (!Number.isInteger(value) || value < lo)
        fail(`${name}: ${path} = ${JSON.stringify(value)}: expected a whole number >= ${lo}`);
    return value;
}

async function fetchText(url) {
    let response;
    try {
        response = await fetch(url);
    } catch (e) {
        fail(`${url}: cannot fetch (${e.message})`);
    }
    if (!response.ok) fail(`${url}: HTTP ${response.status}`);
    return response.text();
}

/// The sidecar's keys this page uses, checked (docs/export.md "Flipbook").
function readSidecar(name, text) {
    let json;
    try {
        json = JSON.parse(text);
    } catch (e) {
        fail(`${name}: not JSON (${e.message})`);
    }
    const book = {
        columns: sidecarInt(name, json, "layout.columns", 1),
        rows: sidecarInt(name, json, "layout.rows", 1),
        width: sidecarInt(name, json, "cell.width", 1),
        height: sidecarInt(name, json, "cell.height", 1),
        frames: sidecarInt(name, json, "frames", 1),
        fps: json.fps,
        image: json.image,
        tileable: json.tileable === true,
    };
    if (book.frames > book.columns * book.rows)
        fail(`${name}: frames = ${book.frames}: expected at most layout.rows x layout.columns = ${book.rows * book.columns}`);
    if (typeof book.fps !== "number" || !(book.fps > 0))
        fail(`${name}: fps = ${JSON.stringify(book.fps)}: expected a number > 0`);
    if (typeof book.image !== "string" || book.image === "")
        fail(`${name}: image = ${JSON.stringify(book.image)}: expected the atlas's file name`);
    if (/\.exr$/i.test(book.image))
        fail(`${name}: image = "${book.image}": expected a PNG atlas (browsers show no EXR: export with -o atlas.png)`);
    return book;
}

function loadImage(url) {
    return new Promise((resolve, reject) => {
        const image = new Image();
        image.onload = () => resolve(image);
        image.onerror = () => reject(new PageError(`${url}: cannot load the image (a PNG atlas: export with -o atlas.png)`));
        image.src = url;
    });
}

const vertexShader = /* glsl */ `
uniform vec2 uCellSize;
uniform float uRepeat;
uniform vec2 uOffset;
out vec2 vTexel;  // position in cell texels, running on across the repeats
void main() {
    // The plane's uv runs up; the atlas's rows run down from the image's top (flipY is off).
    vTexel = vec2(uv.x, 1.0 - uv.y) * uRepeat * uCellSize + uOffset;
    gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
uniform sampler2D uAtlas;
uniform vec2 uAtlasSize;
uniform vec2 uCellSize;
uniform int uColumns;
uniform int uFrame;
uniform int uSampling;  // 0 wrap, 1 clamp, 2 naive
in vec2 vTexel;
out vec4 fragColour;

vec4 texelOfCell(ivec2 origin, vec2 i) {
    return texelFetch(uAtlas, origin + ivec2(mod(i, uCellSize)), 0);
}

void main() {
    ivec2 origin = ivec2(uFrame % uColumns, uFrame / uColumns) * ivec2(uCellSize);
    vec2 local = mod(vTexel, uCellSize);  // the tile's wrap: where the repeated cell starts over
    vec4 colour;
    if (uSampling == 0) {
        // Bilinear over the four nearest texel centres, their indices wrapped within the cell.
        vec2 p = local - 0.5;
        vec2 i0 = floor(p);
        vec2 f = p - i0;
        vec4 top = mix(texelOfCell(origin, i0), texelOfCell(origin, i0 + vec2(1.0, 0.0)), f.x);
        vec4 bottom = mix(texelOfCell(origin, i0 + vec2(0.0, 1.0)), texelOfCell(origin, i0 + 1.0), f.x);
        colour = mix(top, bottom, f.y);
    } else {
        vec2 inCell = uSampling == 1 ? clamp(local, vec2(0.5), uCellSize - 0.5) : local;
        colour = texture(uAtlas, (vec2(origin) + inCell) / uAtlasSize);
    }
    fragColour = vec4(colour.rgb, 1.0);
}`;

const kSamplingNames = ["wrap", "clamp", "naive"];

function makeMaterial(texture, book, options) {
    return new THREE.ShaderMaterial({
        glslVersion: THREE.GLSL3,
        vertexShader,
        fragmentShader,
        uniforms: {
            uAtlas: { value: texture },
            uAtlasSize: { value: new THREE.Vector2(texture.image.width, texture.image.height) },
            uCellSize: { value: new THREE.Vector2(book.width, book.height) },
            uRepeat: { value: options.repeat },
            uOffset: { value: new THREE.Vector2(...options.offset) },
            uColumns: { value: book.columns },
            uFrame: { value: options.frame ?? 0 },
            uSampling: { value: kSamplingNames.indexOf(options.sampling) },
        },
    });
}

function makeTexture(image) {
    const texture = new THREE.Texture(image);
    texture.flipY = false;
    texture.generateMipmaps = false;
    texture.minFilter = THREE.LinearFilter;
    texture.magFilter = THREE.LinearFilter;
    texture.wrapS = texture.wrapT = THREE.ClampToEdgeWrapping;
    texture.colorSpace = THREE.NoColorSpace;  // the bytes as they are
    texture.needsUpdate = true;
    return texture;
}

function readOptions(params, book) {
    const sampling = params.get("sampling") ?? (book.tileable ? "wrap" : "clamp");
    if (!kSamplingNames.includes(sampling))
        fail(`?sampling=${sampling}: expected one of ${kSamplingNames.join(", ")}`);
    return {
        frame: params.has("frame") ? queryInt(params, "frame", 0, 0, book.frames - 1) : null,
        repeat: queryInt(params, "repeat", 3, 1, 64),
        offset: queryOffset(params),
        sampling,
        fps: params.has("fps") ? Number(params.get("fps")) : book.fps,
    };
}

/// The plane as large as the viewport holds at the repeated cells' aspect (the whole viewport
/// when the window is RW x RH pixels: one texel per CSS pixel).
function fitPlane(mesh, camera, book, repeat) {
    const w = window.innerWidth, h = window.innerHeight;
    const scale = Math.min(w / (repeat * book.width), h / (repeat * book.height));
    mesh.scale.set(scale * repeat * book.width, scale * repeat * book.height, 1);
    Object.assign(camera, { left: -w / 2, right: w / 2, top: h / 2, bottom: -h / 2 });
    camera.updateProjectionMatrix();
}

async function start() {
    const params = new URLSearchParams(location.search);
    if (!params.has("sidecar")) fail("no ?sidecar=URL: give the flipbook's JSON sidecar, e.g. ?sidecar=atlas.json");
    const sidecarUrl = new URL(params.get("sidecar"), location.href);
    const book = readSidecar(params.get("sidecar"), await fetchText(sidecarUrl));
    const options = readOptions(params, book);
    if (!(options.fps > 0)) fail(`?fps=${params.get("fps")}: expected a number > 0`);
    const imageUrl = new URL(params.get("image") ?? book.image, sidecarUrl);
    const image = await loadImage(imageUrl.href);
    if (image.width !== book.columns * book.width || image.height !== book.rows * book.height)
        fail(`${imageUrl.pathname}: ${image.width}x${image.height} pixels: expected ${book.columns}x${book.rows} cells of ` +
             `${book.width}x${book.height} = ${book.columns * book.width}x${book.rows * book.height} (the sidecar's layout)`);

    const canvas = document.getElementById("view");
    if (!document.createElement("canvas").getContext("webgl2"))
        fail("this browser gives no WebGL 2 context (the page reads the atlas's texels with texelFetch)");
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio);
    // A shader that does not build would leave the canvas black: say so instead.
    renderer.debug.onShaderError = (gl, program, vertex, fragment) =>
        showError(`the page's shader does not compile here: ${gl.getShaderInfoLog(fragment) || gl.getShaderInfoLog(vertex)}`.trim());
    const scene = new THREE.Scene();
    const camera = new THREE.OrthographicCamera(-1, 1, 1, -1, -1, 1);
    const material = makeMaterial(makeTexture(image), book, options);
    const mesh = new THREE.Mesh(new THREE.PlaneGeometry(1, 1), material);
    scene.add(mesh);
    const resize = () => {
        renderer.setSize(window.innerWidth, window.innerHeight, false);
        fitPlane(mesh, camera, book, options.repeat);
    };
    resize();
    window.addEventListener("resize", resize);
    body.dataset.sampling = options.sampling;
    body.dataset.frames = String(book.frames);

    const t0 = performance.now();
    const draw = () => {
        // Frame i of the loop is shown during [i, i + 1) / fps; the last is followed by the first.
        const time_s = (performance.now() - t0) / 1000;
        const frame = options.frame ?? Math.floor(time_s * options.fps) % book.frames;
        material.uniforms.uFrame.value = frame;
        renderer.render(scene, camera);
        body.dataset.frame = String(frame);
        body.dataset.time = String(time_s);
        body.dataset.ready = "1";
        if (options.frame === null) requestAnimationFrame(draw);
    };
    window.addEventListener("resize", () => options.frame !== null && draw());
    draw();
}

start().catch((e) => showError(e instanceof PageError ? e.message : `unexpected: ${e.message ?? e}`));
