"""The two-mesh avatar of tests/e2e/rig.rs (two_mesh_avatar) from the rig sample: the body
with a material and a morph target `raise`, and a second skinned mesh `Copy`.

Usage: python3 docs/rig/lods_avatar.py data-samples/rig.glb OUT.glb"""
import json, struct, sys
b = open(sys.argv[1], 'rb').read()
jl = struct.unpack('<I', b[12:16])[0]
j = json.loads(b[20:20 + jl])
rest = b[20 + jl:]
bl = struct.unpack('<I', rest[0:4])[0]
bin_ = bytearray(rest[8:8 + bl])
prim = j['meshes'][0]['primitives'][0]
count = j['accessors'][prim['attributes']['POSITION']]['count']
while len(bin_) % 4: bin_.append(0)
off = len(bin_)
for _ in range(count): bin_ += struct.pack('<3f', 0.0, 0.01, 0.0)
j['bufferViews'].append({'buffer': 0, 'byteOffset': off, 'byteLength': 12 * count})
j['accessors'].append({'bufferView': len(j['bufferViews']) - 1, 'componentType': 5126, 'count': count, 'type': 'VEC3', 'min': [0, 0.01, 0], 'max': [0, 0.01, 0]})
j['buffers'][0]['byteLength'] = len(bin_)
prim['targets'] = [{'POSITION': len(j['accessors']) - 1}]
prim['material'] = 0
j['meshes'][0]['weights'] = [0.0]
j['meshes'][0]['extras'] = {'targetNames': ['raise']}
j['materials'] = [{'name': 'skin', 'pbrMetallicRoughness': {'baseColorFactor': [0.8, 0.6, 0.5, 1.0]}}]
copy = json.loads(json.dumps(j['meshes'][0])); copy['name'] = 'Copy'; j['meshes'].append(copy)
sk = next(i for i, n in enumerate(j['nodes']) if 'skin' in n)
node = dict(j['nodes'][sk]); node['name'] = 'copy'; node['mesh'] = 1
j['nodes'].append(node); j['scenes'][0]['nodes'].append(len(j['nodes']) - 1)
js = json.dumps(j).encode()
while len(js) % 4: js += b' '
while len(bin_) % 4: bin_.append(0)
out = struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(bin_)) + struct.pack('<I', len(js)) + b'JSON' + js + struct.pack('<I', len(bin_)) + b'BIN\0' + bytes(bin_)
open(sys.argv[2], 'wb').write(out)
