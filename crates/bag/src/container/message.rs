//! What streaming an MCAP file hands on: each message with its channel's description, and
//! the outcome of the whole file.

/// One message, with what its channel says about it.
pub struct RawMessage<'a> {
    /// Topic.
    pub topic: &'a str,
    /// The schema's name (the ROS type), or "" without a schema.
    pub type_name: &'a str,
    /// The schema's encoding (`ros2msg`) and text.
    pub schema: Option<(&'a str, &'a [u8])>,
    /// The message encoding (`cdr`).
    pub encoding: &'a str,
    /// Log (receive) time, ns since the epoch.
    pub log_time: u64,
    /// The payload.
    pub data: &'a [u8],
}

/// What happened while streaming a file: messages read, and with accepted damage what
/// was lost.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StreamOutcome {
    /// Messages handed to the visitor.
    pub messages: usize,
    /// The damage accepted: skipped records and where reading stopped, one line each.
    pub damage: Vec<String>,
    /// Damaged chunks (or other records) skipped.
    pub skipped_chunks: usize,
}
