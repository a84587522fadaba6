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

// The benchmarks' growing hectare (bench.c's `stand_of("utdb:NoEast:TICO", 20, 5.0,
// 30.0)`): 20 x 20 library lindens 5 m apart in a 106 x 106 x 30 m world, seed 2024.
export function hectare(years) {
  const plants = [];
  for (let i = 0; i < 400; i++) {
    plants.push({ id: `t${i}`, species: 'linden', roots: [[(i % 20 - 9.5) * 5, (Math.floor(i / 20) - 9.5) * 5, 0]] });
  }
  return { format: 'sylva.scenario/1', name: 'hectare of 400 lindens', seed: 2024, iterations: years,
    world: { min: [-53, -53, 0], max: [53, 53, 30] },
    species: { linden: { preset: 'utdb:NoEast:TICO' } }, plants };
}
