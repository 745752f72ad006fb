// A stage's floors share the floor plane: each drummer draws its floor disc only over the
// points nearer to its own pool of light (u_stage_centre) than to any other drummer's
// (u_cell_others, in this drummer's frame), so coplanar discs never fight for a pixel and
// neighbouring pools meet where both are equally bright. One drummer: u_cell_count = 0.
#define MAX_CELL_OTHERS 128
uniform vec2 u_cell_others[MAX_CELL_OTHERS];
uniform int u_cell_count;

bool outside_floor_cell(vec2 p, vec2 own) {
    float d = dot(p - own, p - own);
    for (int i = 0; i < u_cell_count; ++i) {
        vec2 q = p - u_cell_others[i];
        if (dot(q, q) < d) {
            return true;
        }
    }
    return false;
}
