// Surface shading of the viewer: the app's texture (filter) or distances with a colour map and
// isolines (geodesic), under simple headlight shading that keeps hues recognisable.
import * as THREE from "three";

const vertexShader = /* glsl */ `
  varying vec2 vUv;
  varying vec3 vNormal;
  void main() {
    vUv = uv;
    vNormal = normalize(normalMatrix * normal);
    gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
  }`;

// Distance 0 is red, the largest distance blue; no value (inactive texel) is grey.
const fragmentShader = /* glsl */ `
  uniform sampler2D map;
  uniform int mode;
  uniform float scale;
  uniform float isoSpacing;
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
    if (mode == 0) {
      colour = texel.rgb;
    } else if (texel.r < 0.0) {
      colour = vec3(0.5);
    } else {
      float d = texel.r * scale;
      float phase = d / isoSpacing;
      float line = abs(fract(phase - 0.5) - 0.5) / max(fwidth(phase), 1e-6);
      colour = distanceColour(texel.r) * mix(0.35, 1.0, clamp(line, 0.0, 1.0));
    }
    gl_FragColor = vec4(colour * light, 1.0);
  }`;

/// Material for a width x height texture; `size` (model units) scales the isoline spacing.
export function surfaceMaterial(width, height, size) {
  const material = new THREE.ShaderMaterial({
    uniforms: {
      map: { value: null },
      mode: { value: 0 },
      scale: { value: 1.0 },
      isoSpacing: { value: 0.05 },
    },
    vertexShader,
    fragmentShader,
    side: THREE.DoubleSide,
  });
  let rgba = null, scalar = null, scalarData = null;
  const ensure = (format) => {
    if (format === 1 && !rgba) {
      rgba = new THREE.DataTexture(new Uint8Array(4 * width * height), width, height,
                                   THREE.RGBAFormat, THREE.UnsignedByteType);
      rgba.magFilter = THREE.LinearFilter;
      rgba.minFilter = THREE.LinearFilter;
    }
    if (format === 2 && !scalar) {
      scalarData = new Float32Array(width * height);
      scalar = new THREE.DataTexture(scalarData, width, height, THREE.RedFormat, THREE.FloatType);
      scalar.magFilter = THREE.NearestFilter;
      scalar.minFilter = THREE.NearestFilter;
    }
  };
  return {
    material,
    show(frame) {
      const { header, texels } = frame;
      if (header.width !== width || header.height !== height) return;
      ensure(header.format);
      if (header.format === 1) {
        rgba.image.data.set(texels);
        rgba.needsUpdate = true;
        material.uniforms.map.value = rgba;
        material.uniforms.mode.value = 0;
      } else {
        for (let i = 0; i < texels.length; ++i)
          scalarData[i] = texels[i] === 65535 ? -1 : texels[i] / 65534;
        scalar.needsUpdate = true;
        material.uniforms.map.value = scalar;
        material.uniforms.mode.value = 1;
        material.uniforms.scale.value = header.scale;
      }
    },
    /// Isoline spacing as a fraction of the model size.
    setIsoSpacing(fraction) { material.uniforms.isoSpacing.value = fraction * size; },
  };
}
