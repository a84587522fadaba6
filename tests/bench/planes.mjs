// The benchmarks' stand of London planes: 10 x 10 utdb:NoEast:PLAC (a library
// species in years, leaves at its tips' short shoots) 6 m apart in a 66 x 66 x 24 m
// world, planted in 2027. It holds 1,007,109 live internodes after 35 seasons
// (seed 17), with about 600,000 leaves (2 a leaf-bearing node, 0.2 m long).
export function planes100() {
  const plants = [];
  for (let i = 0; i < 10; i++) {
    for (let j = 0; j < 10; j++) {
      plants.push({ id: `p${plants.length + 1}`, species: 'plane', roots: [[-27 + 6 * i, -27 + 6 * j, 0]] });
    }
  }
  return { format: 'sylva.scenario/1', name: '100 London planes', seed: 17, iterations: 35, start_year: 2027,
    world: { min: [-33, -33, 0], max: [33, 33, 24] },
    species: { plane: { preset: 'utdb:NoEast:PLAC' } }, plants };
}
