//! `socnav devices`: the GPU adapters wgpu finds (honouring `WGPU_BACKEND`), and the one that
//! `--backend auto` (hardware GPUs only) and `--backend gpu` (any adapter) would open.

#[cfg(feature = "gpu")]
pub fn devices() -> Result<(), Box<dyn std::error::Error>> {
    use socnav::backend::gpu::{AdapterPolicy, GpuDevice, list_adapters};

    let adapters = list_adapters();
    if adapters.is_empty() {
        println!("no GPU adapters found");
    }
    for a in &adapters {
        let kind = if a.hardware { "hardware" } else { "software" };
        println!("- {a} [{kind}]");
    }
    for (choice, policy) in [
        ("auto", AdapterPolicy::Hardware),
        ("gpu", AdapterPolicy::Any),
    ] {
        match GpuDevice::open(policy) {
            Ok(d) => println!("--backend {choice}: {}", d.adapter.name),
            Err(e) => println!("--backend {choice}: none ({e})"),
        }
    }
    Ok(())
}

#[cfg(not(feature = "gpu"))]
pub fn devices() -> Result<(), Box<dyn std::error::Error>> {
    Err("this build has no GPU backend (built without the `gpu` feature)".into())
}
