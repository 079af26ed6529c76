// Binary payloads of the server (include/texgrad/viewer/protocol.h, viewer_server.h).

/// GET /api/mesh: "TGM1", F, V, 0; u32 triangles[3F]; f32 positions[3V]; f32 corner uvs[6F].
export function decodeMesh(buffer) {
  const head = new Uint32Array(buffer, 0, 4);
  if (head[0] !== 0x314d4754) throw new Error("not a texgrad mesh payload");
  const faces = head[1], vertices = head[2];
  let offset = 16;
  const triangles = new Uint32Array(buffer, offset, 3 * faces);
  offset += 12 * faces;
  const positions = new Float32Array(buffer, offset, 3 * vertices);
  offset += 12 * vertices;
  const uvs = new Float32Array(buffer, offset, 6 * faces);
  return { faces, vertices, triangles, positions, uvs };
}

/// Texture frame: 32-byte header (magic "TGF1", format, width, height, sequence, iteration,
/// residual, scale) and texels in texel order (row 0 = bottom).
export function decodeFrame(buffer) {
  const view = new DataView(buffer);
  if (view.getUint32(0, true) !== 0x31464754) throw new Error("not a texgrad frame");
  const header = {
    format: view.getUint32(4, true),
    width: view.getUint32(8, true),
    height: view.getUint32(12, true),
    sequence: view.getUint32(16, true),
    iteration: view.getUint32(20, true),
    residual: view.getFloat32(24, true),
    scale: view.getFloat32(28, true),
  };
  const n = header.width * header.height;
  const texelBytes = (header.format === 1 ? 4 : 2) * n;
  if (buffer.byteLength < 32 + texelBytes) throw new Error("truncated texgrad frame");
  // Views into the message, no copies: raw bytes (what the page uploads) and typed texels.
  const bytes = new Uint8Array(buffer, 32, texelBytes);
  const texels = header.format === 1 ? bytes : new Uint16Array(buffer, 32, n);
  return { header, bytes, texels };
}
