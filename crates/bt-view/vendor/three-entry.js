// Entry of the vendored three.js bundle (see README.md here): the parts of three.js the
// viewer uses plus OrbitControls, as one IIFE exposing the global `THREE`.
export {
  AmbientLight, BufferGeometry, Color, DirectionalLight, DoubleSide, Float32BufferAttribute,
  Group, Line, LineBasicMaterial, LineLoop, Mesh, MeshBasicMaterial, MeshLambertMaterial,
  PerspectiveCamera, Raycaster, Scene, ShapeUtils, SphereGeometry, Vector2, Vector3,
  WebGLRenderer, GridHelper, AxesHelper, Box3
} from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
