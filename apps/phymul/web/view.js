// The 3-D view: the organs' surfaces coloured by displacement, the obstacles, an orbit camera,
// and picking a node to drag.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { colourAt } from './colours.js';

export const BACKGROUND = 0x20242b;

export class View {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(BACKGROUND);
    this.camera = new THREE.PerspectiveCamera(40, 1, 1e-4, 100);
    this.camera.up.set(0, 0, 1);  // scenes have z up (gravity along -z)
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(1, -1, 2);
    this.scene.add(sun);
    this.pointer = { dragging: false };
    this.obstacles = [];
    this.displacementScale = 1e-3;  // m at the top of the legend; grows with the motion
    this.resize();
    window.addEventListener('resize', () => this.resize());
  }

  resize() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / Math.max(h, 1);
    this.camera.updateProjectionMatrix();
  }

  // The scene description and the triangles (decodeBinary's mesh).
  build(scene, mesh) {
    if (this.mesh) this.scene.remove(this.mesh);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(mesh.rest), 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(mesh.rest.length), 3));
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(mesh.indices), 1));
    const materials = scene.objects.map((o, k) => {
      geometry.addGroup(3 * o.first_triangle, 3 * o.triangles, k);
      const surface = !o.volumetric && o.kind !== 'rigid';
      return new THREE.MeshPhongMaterial({
        vertexColors: o.kind !== 'rigid', color: o.kind === 'rigid' ? 0x9e9e9e : 0xffffff,
        side: THREE.DoubleSide, shininess: 30,
        transparent: surface, opacity: surface ? 0.55 : 1, depthWrite: !surface,
      });
    });
    geometry.computeVertexNormals();
    this.mesh = new THREE.Mesh(geometry, materials);
    this.scene.add(this.mesh);
    this.buildObstacles(scene);
    this.frameCamera(scene);
  }

  buildObstacles(scene) {
    for (const o of this.obstacles) this.scene.remove(o.object);
    this.obstacles = scene.obstacles.map((o) => {
      const material = new THREE.MeshPhongMaterial({ color: 0xb0bec5, transparent: true, opacity: 0.8 });
      const axis = new THREE.Vector3(...o.axis);
      const group = new THREE.Group();
      if (o.shape === 'sphere') {
        group.add(new THREE.Mesh(new THREE.SphereGeometry(o.radius, 32, 16), material));
      } else if (o.shape === 'plane') {
        const plane = new THREE.Mesh(new THREE.PlaneGeometry(2 * scene.size, 2 * scene.size), material);
        plane.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), axis);
        group.add(plane);
      } else {  // capsule (point to point + length axis) or probe (tip at point, open behind)
        const length = o.shape === 'probe' ? 2 * scene.size : o.length;
        const body = new THREE.Mesh(new THREE.CylinderGeometry(o.radius, o.radius, length, 32), material);
        body.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis);
        body.position.copy(axis).multiplyScalar(o.shape === 'probe' ? -length / 2 : length / 2);
        group.add(body, new THREE.Mesh(new THREE.SphereGeometry(o.radius, 32, 16), material));
        if (o.shape === 'capsule') {
          const end = new THREE.Mesh(new THREE.SphereGeometry(o.radius, 32, 16), material);
          end.position.copy(axis).multiplyScalar(length);
          group.add(end);
        }
      }
      group.position.set(...o.point);
      this.scene.add(group);
      return { object: group, point: new THREE.Vector3(...o.point) };
    });
  }

  frameCamera(scene) {
    const [lo, hi] = scene.bounds;
    const centre = new THREE.Vector3(...lo).add(new THREE.Vector3(...hi)).multiplyScalar(0.5);
    const size = Math.max(scene.size, 1e-3);
    this.camera.near = size / 100;
    this.camera.far = size * 100;
    this.camera.position.copy(centre).add(new THREE.Vector3(0.9, -1.6, 0.6).multiplyScalar(size));
    this.camera.updateProjectionMatrix();
    if (!this.controls) this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.target.copy(centre);
    this.controls.update();
  }

  // A frame: positions, colours by displacement, obstacle translations.
  update(frame) {
    if (!this.mesh) return;
    const g = this.mesh.geometry;
    g.attributes.position.array.set(frame.positions);
    g.attributes.position.needsUpdate = true;
    let most = 0;
    for (const d of frame.displacement) most = Math.max(most, d);
    if (most > this.displacementScale) this.displacementScale = most;
    const colour = g.attributes.color.array;
    for (let i = 0; i < frame.displacement.length; ++i)
      colourAt(frame.displacement[i] / this.displacementScale, colour, 3 * i);
    g.attributes.color.needsUpdate = true;
    g.computeVertexNormals();
    g.computeBoundingSphere();
    this.obstacles.forEach((o, k) => {
      o.object.position.set(frame.obstacles[3 * k], frame.obstacles[3 * k + 1], frame.obstacles[3 * k + 2]).add(o.point);
    });
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }

  // The node nearest the surface point under the pointer (client pixels), or null.
  pick(clientX, clientY) {
    if (!this.mesh) return null;
    const ray = this.ray(clientX, clientY);
    const hit = ray.intersectObject(this.mesh)[0];
    if (!hit) return null;
    const p = this.mesh.geometry.attributes.position;
    let best = null, bestDistance = Infinity;
    for (const i of [hit.face.a, hit.face.b, hit.face.c]) {
      const d = new THREE.Vector3().fromBufferAttribute(p, i).distanceTo(hit.point);
      if (d < bestDistance) { best = i; bestDistance = d; }
    }
    return { node: best, point: new THREE.Vector3().fromBufferAttribute(p, best) };
  }

  ray(clientX, clientY) {
    const r = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    return ray;
  }

  // Where the pointer meets the plane through `through` facing the camera.
  pointOnPlane(clientX, clientY, through) {
    const normal = this.camera.getWorldDirection(new THREE.Vector3());
    const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(normal, through);
    return this.ray(clientX, clientY).ray.intersectPlane(plane, new THREE.Vector3());
  }

  // A node's position on screen (client pixels), and whether it faces the camera unhidden.
  screenOf(node) {
    const p = new THREE.Vector3().fromBufferAttribute(this.mesh.geometry.attributes.position, node);
    const s = p.clone().project(this.camera);
    const r = this.canvas.getBoundingClientRect();
    const x = r.left + (s.x + 1) / 2 * r.width, y = r.top + (1 - s.y) / 2 * r.height;
    const hit = this.pick(x, y);
    return { x, y, visible: hit !== null && hit.node === node };
  }
}
