// The parts of three.js the report page uses, bundled into one classic script (global THREE).
export {
  AmbientLight, BoxGeometry, BufferAttribute, BufferGeometry, CapsuleGeometry, Color, CylinderGeometry,
  DirectionalLight, DoubleSide, GridHelper, Group, HemisphereLight, LineBasicMaterial, LineSegments,
  Matrix4, Mesh, MeshLambertMaterial, PerspectiveCamera, Quaternion, Scene, SphereGeometry, Vector3,
  WebGLRenderer, Float32BufferAttribute
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
