// requires: common/sngnn_graph_build.wgsl
//
// Twin of src/systems/sngnn_graph.rs (stage `sngnn_graph`, run only with the SNGNN-v2 reward;
// docs/spec.md 7.2-7.4). For every stepping environment whose step is not terminal (none of the
// outcome flags the termination stage raised): record the frame into the history
// (src/sngnn/frame.rs `record`, what the CPU stage does), then build the graph into the packed
// regions (`graph::build` then `PackedLayout::pack`; on the CPU, stage `sngnn_score` builds it
// into its scorer's scratch). Every other environment's packed graph gets no nodes (the rest of
// it is left as it was), so that the next stage's network (`sngnn_score`) skips it.
// Needs the SNGNN prelude and bindings (`GpuStages::with_sngnn_graphs`).

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs) {
        return;
    }
    let row = batch.co_info + e * batch.so_info;
    let terminal = outf[row + INFO_OUT_OF_MAP] != 0.0 || outf[row + INFO_SUCCESS] != 0.0
        || outf[row + INFO_COLLISION] != 0.0 || outf[row + INFO_TIMEOUT] != 0.0;
    if (su[batch.c_stepping + e] == 0u || terminal) {
        sn_gu[sn_ubase(e) + SN_WORD_NODES] = 0u;
        return;
    }
    sn_record(e);
    sn_build_graph(e);
}
