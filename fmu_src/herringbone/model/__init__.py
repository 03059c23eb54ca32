"""The gear train as data and equations' inputs: `parameters` (every parameter and output:
value, unit, range, component), `scene` (loading and validation), `geometry` (the gears),
`mesh` (contact points and their switches), `assembly` (GearTrainModel: the model assembled from
its elements: arrays, stiffness and damping matrices, statics, modes), `document` (the
parameter tables of docs/model.md)."""
