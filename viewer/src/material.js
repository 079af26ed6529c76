// Surface shading of the viewer: the app's texture (filter; stitch with its locked texels tinted)
// or distances with a colour map and isolines (geodesic), under simple headlight shading that
// keeps hues recognisable.
import * as THREE from "three";

const vertexShader = /* glsl */ `
  varying vec2 vUv;
  varying vec3 vNormal;
  void main() {
    vUv = uv;
    vNormal = normalize(normalMatrix * normal);
    gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
  }`;

// Distance 0 is red, the largest distance blue; no value (inactive texel) is grey. Distances
// arrive as 16-bit codes uploaded unconverted as two 8-bit channels (low, high byte) and are
// decoded here, so the page does no per-texel work (code 65535 = no value, else code / 65534).
const fragmentShader = /* glsl */ `
  uniform sampler2D map;
  uniform int mode;
  uniform float scale;
  uniform float isoSpacing;
  uniform bool lockTint;
  varying vec2 vUv;
  varying vec3 vNormal;
  vec3 distanceColour(float t) {
    return clamp(vec3(1.0 - 2.0 * t, 1.0 - abs(2.0 * t - 1.0), 2.0 * t - 1.0), 0.0, 1.0) * 0.8 +
           vec3(0.2 * (1.0 - t), 0.0, 0.2 * t);
  }
  void main() {
    float light = 0.65 + 0.35 * abs(normalize(vNormal).z);
    vec4 texel = texture2D(map, vUv);
    vec3 colour;
    float code = floor(texel.r * 255.0 + 0.5) + 256.0 * floor(texel.g * 255.0 + 0.5);
    if (mode == 0) {
      colour = texel.rgb;
      // stitch: alpha 0 marks locked texels; tint them cyan.
      if (lockTint) colour = mix(colour, vec3(0.1, 0.85, 1.0), 0.45 * (1.0 - texel.a));
    } else if (code > 65534.5) {
      colour = vec3(0.5);
    } else {
      float t = code / 65534.0;
      float phase = t * scale / isoSpacing;
      float line = abs(fract(phase - 0.5) - 0.5) / max(fwidth(phase), 1e-6);
      colour = distanceColour(t) * mix(0.35, 1.0, clamp(line, 0.0, 1.0));
    }
    gl_FragColor = vec4(colour * light, 1.0);
  }`;

/// Material for a width x height texture; `size` (model units) scales the isoline spacing; `side`
/// says which faces to draw (visible_side.js).
export function surfaceMaterial(width, height, size, side = THREE.DoubleSide) {
  const material = new THREE.ShaderMaterial({
    uniforms: {
      map: { value: null },
      mode: { value: 0 },
      scale: { value: 1.0 },
      isoSpacing: { value: 0.05 },
      lockTint: { value: false },
    },
    vertexShader,
    fragmentShader,
    side,
  });
  // One texture per format; show() points it at the frame's bytes (no copy, no conversion) and
  // WebGL uploads them on the next render.
  const textures = new Map();
  const texture = (format, data) => {
    let t = textures.get(format);
    if (!t) {
      t = format === 1
          ? new THREE.DataTexture(data, width, height, THREE.RGBAFormat, THREE.UnsignedByteType)
          : new THREE.DataTexture(data, width, height, THREE.RGFormat, THREE.UnsignedByteType);
      const filter = format === 1 ? THREE.LinearFilter : THREE.NearestFilter;
      t.magFilter = filter;
      t.minFilter = filter;
      t.generateMipmaps = false;
      t.unpackAlignment = 1;
      textures.set(format, t);
    }
    t.image.data = data;
    t.needsUpdate = true;
    return t;
  };
  return {
    material,
    /// Shows a decoded frame; returns false if it does not fit the texture.
    show(frame) {
      const { header, bytes } = frame;
      if (header.width !== width || header.height !== height) return false;
      if (header.format !== 1 && header.format !== 2) return false;
      material.uniforms.map.value = texture(header.format, bytes);
      material.uniforms.mode.value = header.format === 1 ? 0 : 1;
      if (header.format === 2) material.uniforms.scale.value = header.scale;
      return true;
    },
    /// Stitch: tint texels whose alpha is 0 (the lock mask the stitch app sends in alpha).
    setLockTint(on) { material.uniforms.lockTint.value = on; },
    /// Isoline spacing as a fraction of the model size.
    setIsoSpacing(fraction) { material.uniforms.isoSpacing.value = fraction * size; },
  };
}
