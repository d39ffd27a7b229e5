//! Record synthetic 1 KiB messages into a bag directory until the disk is full, then print
//! the writer's error and what the sealed bag holds. Used to check real ENOSPC handling on a
//! tiny tmpfs (`mount -t tmpfs -o size=1m tmpfs /mnt/tiny`):
//!
//! `cargo run -p metrocell-bag --example record_until_full -- /mnt/tiny/bag`

use metrocell_bag::{info, BagReader, BagWriter, MessageFilter, WriterOptions};

fn main() {
    let dir = std::env::args()
        .nth(1)
        .expect("usage: record_until_full <bag dir>");
    let opts = WriterOptions {
        chunk_size: 16 * 1024,
        ..Default::default()
    };
    let mut w = BagWriter::create(&dir, opts).expect("create bag");
    w.add_topic("/blob", "std_msgs/msg/UInt8MultiArray", BLOB_DEF, "")
        .expect("topic");
    let mut n = 0u64;
    let err = loop {
        // Incompressible payload so the disk fills quickly despite zstd.
        let mut data = vec![0u8, 1, 0, 0];
        let mut x = n.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        data.extend((0..1024).map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        }));
        if let Err(e) = w.write("/blob", 1_000 + n * 1_000_000, 0, &data) {
            break e;
        }
        n += 1;
        if n % 100 == 0 {
            if let Err(e) = w.flush() {
                break e;
            }
        }
    };
    println!("wrote {n} messages, then: {err}");
    drop(w);
    let r = BagReader::open(&dir).expect("sealed bag opens strictly");
    println!(
        "bag holds {} messages",
        r.read_all(&MessageFilter::default()).unwrap().len()
    );
    print!("{}", info(&dir).unwrap());
}

const BLOB_DEF: &str = "std_msgs/MultiArrayLayout layout\nuint8[] data\n\
================================================================================\n\
MSG: std_msgs/MultiArrayLayout\nstd_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n\
================================================================================\n\
MSG: std_msgs/MultiArrayDimension\nstring label\nuint32 size\nuint32 stride\n";
