//! The GPU scan and radix sort the RastaVox build relies on, against the CPU on sizes
//! that span several tiles, blocks and rounds of the single-workgroup block scan.

use ssbvb_gpu::kernels::radix_sort::{GpuRadixSort, SortBuffers};
use ssbvb_gpu::kernels::scan::GpuScan;
use ssbvb_gpu::kernels::{read_words, storage_init};
use ssbvb_gpu::wgpu;

fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

fn encoder(ctx: &ssbvb_gpu::GpuContext) -> wgpu::CommandEncoder {
    ctx.device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("test"),
        })
}

#[test]
fn scan_matches_the_cpu_prefix_sum() {
    let ctx = ssbvb_tests::ctx();
    let scan = GpuScan::new(ctx).unwrap();
    // 300 000 values: 293 blocks, so the block-sum scan runs two rounds; 1 and 1025 are
    // the edges of one block.
    for n in [1u32, 1025, 300_000] {
        let mut r = xorshift(u64::from(n) * 77 + 1);
        let data: Vec<u32> = (0..n).map(|_| (r() % 1000) as u32).collect();
        let buf = storage_init(&ctx.device, "scan data", &data);
        let mut enc = encoder(ctx);
        let sums = scan.record(&ctx.device, &mut enc, &buf, n);
        ctx.queue.submit([enc.finish()]);
        let got = read_words(ctx, &buf, 0, u64::from(n)).unwrap();
        let mut expect = Vec::with_capacity(n as usize);
        let mut acc = 0u32;
        for v in &data {
            expect.push(acc);
            acc += v;
        }
        assert_eq!(got, expect, "n = {n}");
        let total = read_words(ctx, &sums, GpuScan::total_index(n), 1).unwrap()[0];
        assert_eq!(total, acc, "n = {n}");
        assert!(ctx.take_uncaptured_errors().is_empty());
    }
}

#[test]
fn radix_sort_is_a_stable_sort_on_the_low_key_bits() {
    let ctx = ssbvb_tests::ctx();
    let sort = GpuRadixSort::new(ctx).unwrap();
    // Bits 40..48 of the key carry a tag that must travel with it but not be sorted on.
    for (n, bits) in [(5000u32, 40u32), (3000, 36), (1, 8)] {
        let mut r = xorshift(u64::from(n) + 5);
        // 300 distinct full-width keys, so every digit of every pass varies and equal
        // keys are common (stability).
        let distinct: Vec<u64> = (0..300).map(|_| r() & ((1u64 << bits) - 1)).collect();
        let keys: Vec<u64> = (0..n)
            .map(|_| distinct[(r() % 300) as usize] | (r() % 7) << 40)
            .collect();
        let lo: Vec<u32> = keys.iter().map(|k| *k as u32).collect();
        let hi: Vec<u32> = keys.iter().map(|k| (k >> 32) as u32).collect();
        let val: Vec<u32> = (0..n).collect();
        let data = SortBuffers {
            lo: storage_init(&ctx.device, "lo", &lo),
            hi: storage_init(&ctx.device, "hi", &hi),
            val: storage_init(&ctx.device, "val", &val),
        };
        let scratch = SortBuffers::new(&ctx.device, "scratch", u64::from(n));
        let mut enc = encoder(ctx);
        let in_scratch = sort.record(&ctx.device, &mut enc, &data, &scratch, n, bits);
        ctx.queue.submit([enc.finish()]);
        let out = if in_scratch { &scratch } else { &data };
        let read = |b: &wgpu::Buffer| read_words(ctx, b, 0, u64::from(n)).unwrap();
        let (glo, ghi, gval) = (read(&out.lo), read(&out.hi), read(&out.val));
        let mut expect: Vec<(u64, u32)> = keys.iter().copied().zip(0..n).collect();
        expect.sort_by_key(|&(k, _)| k & ((1u64 << bits) - 1));
        for i in 0..n as usize {
            let k = u64::from(glo[i]) | u64::from(ghi[i]) << 32;
            assert_eq!((k, gval[i]), expect[i], "n = {n}, entry {i}");
        }
        assert!(ctx.take_uncaptured_errors().is_empty());
    }
}
