// The benchmarks' 100-tree stand: igm-fig17b with an upward tropism, 10 x 10
// trees 2 m apart in a 26 x 26 x 14 m world.
export function stand100() {
  const plants = [];
  for (let i = 0; i < 10; i++) {
    for (let j = 0; j < 10; j++) {
      plants.push({ id: `t${plants.length + 1}`, species: 'tree', roots: [[-9 + 2 * i, -9 + 2 * j, 0]] });
    }
  }
  return { format: 'sylva.scenario/1', name: '100-tree stand', seed: 17, iterations: 24,
    world: { min: [-13, -13, 0], max: [13, 13, 14] },
    species: { tree: { preset: 'igm-fig17b', tropism: [0, 0, 1] } }, plants };
}
